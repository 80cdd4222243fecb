#pragma once
// Thin-lens helpers: lens points on the aperture disk.
#include <cmath>

namespace aperture {

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

}  // namespace aperture
