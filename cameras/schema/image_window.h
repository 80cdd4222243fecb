#pragma once
// The image window of the planar cameras: where the W x H raster lies on the image plane
// (viewport vw x vh, shifted by `shift` viewports). The one owner of the shift formula:
//   u = (x / W − ½ + sx)·vw,   v = (−(y / H − ½) + sy)·vh
// for raster position (x, y) (pixel (i, j) centre at (j + ½, i + ½)); the plane's origin, the
// point on the view axis (the principal point), is at raster ((½ − sx)·W, (½ + sy)·H).
#include <cstddef>
#include <glm/glm.hpp>
#include <vector>

namespace aperture {

struct ImageWindow {
  int width = 1, height = 1;  ///< pixels
  double vw = 1, vh = 1;      ///< viewport on the image plane, scene units
  glm::dvec2 shift{0.0};      ///< viewports

  double u(double x) const { return (x / width - 0.5 + shift.x) * vw; }
  double v(double y) const { return (-(y / height - 0.5) + shift.y) * vh; }
  /// Raster position of image-plane point (u, v) (the inverse of u(), v()).
  glm::dvec2 raster(double u, double v) const {
    return {(u / vw - shift.x + 0.5) * width, (0.5 - (v / vh - shift.y)) * height};
  }
  double uLo() const { return (shift.x - 0.5) * vw; }
  double uHi() const { return (shift.x + 0.5) * vw; }
  double vLo() const { return (shift.y - 0.5) * vh; }
  double vHi() const { return (shift.y + 0.5) * vh; }
  /// The raster position of the principal point (the plane's origin).
  glm::dvec2 principalPoint() const { return raster(0.0, 0.0); }
  /// The shift that moves the window by dx pixels right and dy pixels up: (dx / W, dy / H).
  static glm::dvec2 shiftForPixelOffset(double dx, double dy, int width, int height) {
    return {dx / width, dy / height};
  }
  /// The shift that puts the principal point at raster position (px, py).
  static glm::dvec2 shiftForPrincipalPoint(double px, double py, int width, int height) {
    return {0.5 - px / width, py / height - 0.5};
  }
};

/// The image-plane coordinates of every pixel centre, computed once per camera: u of column
/// j's centre (window.u(j + ½)) and v of row i's (window.v(i + ½)). The raster centres are
/// exact in double, so the entries are the per-ray values bit for bit, and the pixel-centre
/// kernels need no per-ray divide for them. 16 entries past the right and bottom edges serve
/// the lanes of a block that crosses them (finite rays, never traced).
struct PixelCentreTable {
  static constexpr size_t kPastEdge = 16;
  std::vector<double> u, v;

  PixelCentreTable() = default;
  explicit PixelCentreTable(const ImageWindow& w)
      : u(size_t(w.width) + kPastEdge), v(size_t(w.height) + kPastEdge) {
    for (size_t j = 0; j < u.size(); ++j) u[j] = w.u(double(j) + 0.5);
    for (size_t i = 0; i < v.size(); ++i) v[i] = w.v(double(i) + 0.5);
  }
};

}  // namespace aperture
