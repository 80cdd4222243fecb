#pragma once
// Per-sensor tables of ray directions: the unit camera-space direction (OpenCV axes) of every
// pixel centre of a calibrated sensor, computed once by the lens's exact inverse and shared
// by every image (and every thread) that uses the sensor. A distorted camera then costs a
// table read and a rotation per ray, like a pinhole.
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "cameras/lenses/calibration.h"
#include "core/util/huge_pages.h"

namespace aperture {

class DirectionTable {
 public:
  /// The table of `sensor`: from a small process-wide cache (the most recently used sensors),
  /// or computed in parallel and added to it. Thread-safe.
  static std::shared_ptr<const DirectionTable> of(const CalibratedSensor& sensor);
  /// Whether the cache of `of` holds the table of `sensor` (built and not yet dropped).
  static bool cached(const CalibratedSensor& sensor);
  /// What the cache of `of` keeps: the most recent tables up to this many bytes (and the most
  /// recent one whatever its size).
  static constexpr size_t kCacheBytes = size_t(1) << 30;
  /// The bytes a table of a width x height sensor holds (bytes() of its table).
  static size_t bytesFor(int width, int height);
  /// At most how many bytes of tables the cache and a camera being made hold at once when
  /// cameras of these sensors are made one after the other (each distinct sensor counted
  /// once): every table while they fit in kCacheBytes, else the cache's bound plus the
  /// largest table, being computed beside it. For --max-memory.
  static size_t peakBytes(const std::vector<CalibratedSensor>& sensors);
  /// Computes the table (no cache).
  explicit DirectionTable(const CalibratedSensor& sensor);

  /// The unit direction of pixel (row i, column j)'s centre; where valid(i, j) is false (no
  /// ray) it holds the optical axis (0, 0, 1), so a packet needs no branch.
  glm::dvec3 at(int i, int j) const {
    const size_t k = index(i, j);
    return {x_[k], y_[k], z_[k]};
  }
  bool valid(int i, int j) const { return valid_[index(i, j)] != 0; }

  /// Storage: structure of arrays (x, y, z, valid), in blocks of 4 x 4 pixels, each block's
  /// 16 entries row by row, blocks row by row: a packet of the frame loop (4 x 4, 4 x 2 or
  /// 2 x 2 pixels on a grid of 4) reads a few contiguous runs, and the packets of a tile walk
  /// forward through memory, which the hardware prefetcher follows (a table of a 1080p image
  /// is 50 MB: it does not stay in cache).
  static constexpr int kBlock = 4;
  size_t index(int i, int j) const {
    const size_t block = size_t(i / kBlock) * blocksPerRow_ + size_t(j / kBlock);
    return block * (kBlock * kBlock) + size_t((i % kBlock) * kBlock + j % kBlock);
  }
  const double* x() const { return x_.data(); }
  const double* y() const { return y_.data(); }
  const double* z() const { return z_.data(); }
  const unsigned char* validity() const { return valid_.data(); }

  /// Where the rays of each block of kBlock x kBlock pixels cross the plane z = 1, (d.x /
  /// d.z, d.y / d.z): (x0, y0, x1, y1), blocks row by row, rounded outwards to float; x0 > x1
  /// for a block without a ray. Meaningful where minCosine() > 0 (every ray in front).
  const std::vector<glm::vec4>& planeBounds() const { return planeBounds_; }
  /// The same over every ray.
  glm::dvec4 planeExtent() const { return planeExtent_; }
  /// The least cosine of a ray with the optical axis (its z; 1 without rays).
  double minCosine() const { return minCosine_; }
  /// Per block (as planeBounds), the pixels with a ray: bit r·kBlock + c for the pixel in the
  /// block's row r and column c (none past the image's edges).
  const std::vector<uint16_t>& blockRays() const { return blockRays_; }

  /// Pixels with a ray, of width x height.
  size_t validCount() const;
  size_t bytes() const {
    return 3 * x_.size() * sizeof(double) + valid_.size() +
           planeBounds_.size() * (sizeof(glm::vec4) + sizeof(uint16_t));
  }
  const CalibratedSensor& sensor() const { return sensor_; }

 private:
  /// Fills planeBounds_, planeExtent_ and minCosine_ from the directions.
  void boundPlaneCrossings(size_t blockRows);

  CalibratedSensor sensor_;
  size_t blocksPerRow_ = 0;
  LargeBuffer<double> x_, y_, z_;
  LargeBuffer<unsigned char> valid_;
  std::vector<glm::vec4> planeBounds_;
  std::vector<uint16_t> blockRays_;
  glm::dvec4 planeExtent_{0.0};
  double minCosine_ = 1;
};

/// The unit camera-space direction (OpenCV axes) of aperture raster position (x, y) of
/// `sensor` (pixel (i, j) centre at (j + ½, i + ½)): the source's pixel convention applied
/// (sourcePixelOfRaster), then the lens's inverse. Nothing where the pixel has no ray. The
/// one formula the tables and the off-centre samples use.
std::optional<glm::dvec3> sensorDirection(const CalibratedSensor& sensor, double x, double y);

}  // namespace aperture
