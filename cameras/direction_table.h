#pragma once
// Per-sensor tables of ray directions: the unit camera-space direction (OpenCV axes) of every
// pixel centre of a calibrated sensor, computed once by the lens's exact inverse and shared
// by every image (and every thread) that uses the sensor. A distorted camera then costs a
// table read and a rotation per ray, like a pinhole.
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "cameras/calibration.h"

namespace aperture {

class DirectionTable {
 public:
  /// The table of `sensor`: from a small process-wide cache (the most recently used sensors),
  /// or computed in parallel and added to it. Thread-safe.
  static std::shared_ptr<const DirectionTable> of(const CalibratedSensor& sensor);
  /// Computes the table (no cache).
  explicit DirectionTable(const CalibratedSensor& sensor);

  /// The unit direction of pixel (row i, column j)'s centre; where valid(i, j) is false (no
  /// ray) it holds the optical axis (0, 0, 1), so a packet needs no branch.
  glm::dvec3 at(int i, int j) const {
    const size_t k = index(i, j);
    return {x_[k], y_[k], z_[k]};
  }
  bool valid(int i, int j) const { return valid_[index(i, j)] != 0; }
  /// Row pointers (structure of arrays, so a block's loop vectorises): the components of the
  /// directions and the validity (1: a ray, 0: none) of row i from column j on.
  struct Row {
    const double *x, *y, *z;
    const unsigned char* valid;
  };
  Row row(int i, int j) const {
    const size_t k = index(i, j);
    return {&x_[k], &y_[k], &z_[k], &valid_[k]};
  }
  /// Pixels with a ray, of width x height.
  size_t validCount() const;
  size_t bytes() const { return 3 * x_.size() * sizeof(double) + valid_.size(); }
  const CalibratedSensor& sensor() const { return sensor_; }

 private:
  size_t index(int i, int j) const { return size_t(i) * size_t(width_) + size_t(j); }

  CalibratedSensor sensor_;
  int width_ = 0;
  std::vector<double> x_, y_, z_;
  std::vector<unsigned char> valid_;
};

/// The unit camera-space direction (OpenCV axes) of aperture raster position (x, y) of
/// `sensor` (pixel (i, j) centre at (j + ½, i + ½)): the source's pixel convention applied
/// (sourcePixelOfRaster), then the lens's inverse. Nothing where the pixel has no ray. The
/// one formula the tables and the off-centre samples use.
std::optional<glm::dvec3> sensorDirection(const CalibratedSensor& sensor, double x, double y);

}  // namespace aperture
