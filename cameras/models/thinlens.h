#pragma once
// Thin-lens helpers: lens points on the aperture disk, and the rays through pixel centres and
// the lens centre.
#include <cmath>
#include <glm/glm.hpp>

#include "cameras/schema/image_window.h"
#include "cameras/schema/params.h"
#include "core/engine/camera.h"

namespace aperture {

/// The thin lens's focus distance: given, else |at − eye| with a look-at point, else the focus
/// spec's default.
double focusDistanceOf(const CameraParams& p);

/// Concentric (Shirley–Chiu) map of the unit square onto the unit disk: the square
/// [-1, 1]² is cut into four triangles by its diagonals, and each concentric square ring of
/// radius r = max(|a|, |b|) becomes the circle of radius r, so strata stay compact and the
/// area is preserved. (½, ½) maps to the centre (0, 0) exactly.
inline void concentricDisk(double sx, double sy, double& diskX, double& diskY) {
  constexpr double kQuarterPi = 0.78539816339744830962;
  const double a = 2.0 * sx - 1.0, b = 2.0 * sy - 1.0;
  if (a == 0.0 && b == 0.0) {
    diskX = 0.0;
    diskY = 0.0;
    return;
  }
  double r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = kQuarterPi * (b / a);
  } else {
    r = b;
    phi = 2.0 * kQuarterPi - kQuarterPi * (a / b);
  }
  diskX = r * std::cos(phi);
  diskY = r * std::sin(phi);
}

/// What the thin lens's pixel-centre kernel needs of the camera (PerspectiveCamera with a lens
/// radius r > 0): at the lens centre (lens sample (½, ½), every sample at 1 spp and the centre
/// ray at any spp) the lens point is L = r·(0·U + 0·V), a constant (±0 per component).
struct ThinLensCentres {
  const double* columnU;  ///< u of column j's centre (PerspectiveCamera's table)
  const double* rowV;     ///< v of row i's centre
  int width, height;
  glm::dvec3 u, v, dW;  ///< U, V and d·W
  double focusOverD;    ///< f / d
  glm::dvec3 lens;      ///< L at the lens centre
  glm::dvec3 origin;    ///< render-space e + L
};

/// Fills a block of thin-lens rays through pixel centres and the lens centre with
/// PerspectiveCamera::rayAt's expressions term by term (toFocus = (f/d)·pinhole − L,
/// toFocus / |toFocus|), as a vector kernel, with valid −1 inside the width x height image and
/// 0 past it. False, filling nothing, for block shapes other than the frame loop's.
bool generateThinLensCentres(const ThinLensCentres& c, const PacketRequest& req, RayLanes& out,
                             int* valid);

}  // namespace aperture
