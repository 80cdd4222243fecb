// The formulas of FOV, the division models, EUCM, RAD_TAN_THIN_PRISM_FISHEYE and
// EQUIRECTANGULAR (cameras/lens_formulas.h). The first four are radial profiles ρ(θ) over the
// angle θ off-axis, so each sees whatever its formula reaches, behind the camera included (the
// division model with k < 0, EUCM with α > ½); EQUIRECTANGULAR is a map of its own.
#include "cameras/lenses/lens_formulas.h"

#include <cmath>
#include <limits>

#include "core/util/error.h"

namespace aperture {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

// ---- FOV: COLMAP's Distortion maps the normalised radius r = tan θ to
// ρ = atan(2 r tan(ω/2)) / ω (ρ = r for ω = 0) and its Undistortion back by
// r = tan(ρω) / (2 tan(ω/2)), which exists while ρω < π/2. COLMAP's ImgFromCam takes z > 0
// only: θ < 90°.

void fovProfile(const double* k, double theta, double& rho, double& drho) {
  const double omega = k[0];
  if (!(theta < kPi / 2)) {
    rho = drho = kNaN;
    return;
  }
  const double t = std::tan(theta), sec2 = 1 + t * t;
  if (omega == 0) {
    rho = t, drho = sec2;
    return;
  }
  const double a = 2 * std::tan(omega / 2);
  rho = std::atan(a * t) / omega;
  drho = a * sec2 / (omega * (1 + a * a * t * t));
}

double fovInverse(const double* k, double rho) {
  const double omega = k[0];
  if (omega == 0) return std::atan(rho);
  return std::atan(std::tan(rho * omega) / (2 * std::tan(omega / 2)));
}

void fovCheck(const char* model, const double* k) {
  if (!(std::abs(k[0]) < kPi))
    throw Error(cat("camera model ", model, ": omega = ", k[0],
                    " must lie in (-π, π) (the field of view, in radians)"));
}

// ---- The division model: COLMAP's CamFromImg gives the ray (x, y, 1 + kρ²) of the distorted
// point (x, y), ρ = |(x, y)|, so θ(ρ) = atan2(ρ, 1 + kρ²), whose derivative is
// (1 − kρ²) / (ρ² + (1 + kρ²)²). Its ImgFromCam (no cheirality test) solves the quadratic for
// ρ of the ray at θ: ρ = 2 sin θ / (cos θ + √D), D = cos²θ − 4k sin²θ (the root nearer the
// axis), written as (√D − cos θ) / (−2k sin θ) behind the camera, where the first form
// cancels. For k < 0, θ(ρ) grows from 0 to 180° over all ρ: every pixel has a ray, those past
// ρ = 1/√−k behind the camera. For k > 0, ρ(θ) folds at ρ = 1/√k (D = 0), θ = atan(1/(2√k)).

void divisionProfile(const double* k, double theta, double& rho, double& drho) {
  const double kk = k[0], s = std::sin(theta), c = std::cos(theta);
  const double d = c * c - 4 * kk * s * s;
  rho = kNaN;
  if (d >= 0 && theta < kPi) {
    if (c >= 0)
      rho = 2 * s / (c + std::sqrt(d));
    else if (kk < 0)
      rho = (std::sqrt(d) - c) / (-2 * kk * s);
  }
  const double q = 1 + kk * rho * rho;
  drho = (rho * rho + q * q) / (1 - kk * rho * rho);
}

double divisionInverse(const double* k, double rho) {
  return std::atan2(rho, 1 + k[0] * rho * rho);
}

// ---- EUCM: COLMAP's ImgFromCam divides (x, y) by α·√(β(x² + y²) + z²) + (1 − α)·z, which for
// the unit ray at θ is ρ = sin θ / (α √(β sin²θ + cos²θ) + (1 − α) cos θ) while the divisor is
// positive. Its CamFromImg gives the ray (x, y, m) of the distorted point, m = (1 − α²βρ²) /
// (α √(1 − (2α − 1)βρ²) + 1 − α): θ = atan2(ρ, m). COLMAP refuses α outside [0, 1] and β <= 0
// (EUCMCameraModel::HasBogusExtraParams).

void eucmProfile(const double* k, double theta, double& rho, double& drho) {
  const double alpha = k[0], beta = k[1], s = std::sin(theta), c = std::cos(theta);
  const double q = std::sqrt(beta * s * s + c * c);
  const double den = alpha * q + (1 - alpha) * c;
  if (!(den > 0) || !(theta < kPi)) {
    rho = drho = kNaN;
    return;
  }
  const double dden = alpha * (beta - 1) * s * c / q - (1 - alpha) * s;
  rho = s / den;
  drho = (c * den - s * dden) / (den * den);
}

double eucmInverse(const double* k, double rho) {
  const double alpha = k[0], beta = k[1], r2 = rho * rho;
  const double m = (1 - alpha * alpha * beta * r2) /
                   (alpha * std::sqrt(1 - (2 * alpha - 1) * beta * r2) + 1 - alpha);
  return std::atan2(rho, m);
}

void eucmCheck(const char* model, const double* k) {
  if (!(k[0] >= 0 && k[0] <= 1))
    throw Error(cat("camera model ", model, ": alpha = ", k[0], " must lie in [0, 1]"));
  if (!(k[1] > 0)) throw Error(cat("camera model ", model, ": beta = ", k[1], " must be > 0"));
}

// ---- RAD_TAN_THIN_PRISM_FISHEYE: COLMAP's Distortion takes the fisheye point (u, v) = θ·(x, y)
// /|(x, y)| to (x', y') = g·(u, v), g = 1 + k0θ² + k1θ⁴ + … + k5θ¹², and adds to it, with
// r² = x'² + y'², the tangential terms (2 p1 x'y' + p0 (r² + 2x'²), 2 p0 x'y' + p1 (r² + 2y'²))
// and the thin prism (s0 r² + s1 r⁴, s2 r² + s3 r⁴).

void radTanProfile(const double* k, double theta, double& rho, double& drho) {
  const double s = theta * theta;
  double g = k[5], dg = 13 * k[5];
  for (int i = 4; i >= 0; --i) g = g * s + k[i], dg = dg * s + (2 * i + 3) * k[i];
  rho = theta * (1 + g * s);
  drho = 1 + dg * s;
}

void radTanNonRadial(const double* k, double x, double y, double& dx, double& dy, double* j) {
  const double p0 = k[6], p1 = k[7], s0 = k[8], s1 = k[9], s2 = k[10], s3 = k[11];
  const double r2 = x * x + y * y;
  dx = 2 * p1 * x * y + p0 * (r2 + 2 * x * x) + s0 * r2 + s1 * r2 * r2;
  dy = 2 * p0 * x * y + p1 * (r2 + 2 * y * y) + s2 * r2 + s3 * r2 * r2;
  if (!j) return;
  j[0] = 2 * p1 * y + 6 * p0 * x + 2 * s0 * x + 4 * s1 * r2 * x;  // d(dx)/dx
  j[1] = 2 * p0 * y + 2 * p1 * x + 2 * s2 * x + 4 * s3 * r2 * x;  // d(dy)/dx
  j[2] = 2 * p1 * x + 2 * p0 * y + 2 * s0 * y + 4 * s1 * r2 * y;  // d(dx)/dy
  j[3] = 2 * p0 * x + 6 * p1 * y + 2 * s2 * y + 4 * s3 * r2 * y;  // d(dy)/dy
}

// Inside |(x', y')| <= R the terms above move a point by at most
// 4(|p0| + |p1|)R² + (|s0| + |s2|)R² + (|s1| + |s3|)R⁴.
double radTanReach(const double* k, double radius) {
  const double r2 = radius * radius;
  return (4 * (std::abs(k[6]) + std::abs(k[7])) + std::abs(k[8]) + std::abs(k[10])) * r2 +
         (std::abs(k[9]) + std::abs(k[11])) * r2 * r2;
}

// ---- EQUIRECTANGULAR: COLMAP's ImgFromCam takes the azimuth θ = atan2(x, z) (from +z, +x at
// +π/2) and the elevation φ = atan2(−y, √(x² + z²)) (−y up) of any non-zero (x, y, z) to
// ((θ/2π + ½)·w, (½ − φ/π)·h); CamRayFromImg inverts it for every pixel: the ray
// (cos φ sin θ, −sin φ, cos φ cos θ). A position off the image [0, w] × [0, h] has no ray
// (it would wrap around). As a linear map of the angles its intrinsics are
// fx = w/2π, fy = h/π (pixels per radian) and (cx, cy) = (w/2, h/2).

bool equirectRay(const double* k, double px, double py, double dir[3]) {
  if (!(px >= 0 && px <= k[0] && py >= 0 && py <= k[1])) return false;  // off the image
  const double theta = 2 * kPi * (px / k[0] - 0.5), phi = kPi * (0.5 - py / k[1]);
  const double c = std::cos(phi);
  dir[0] = c * std::sin(theta), dir[1] = -std::sin(phi), dir[2] = c * std::cos(theta);
  return std::isfinite(dir[0]) && std::isfinite(dir[1]) && std::isfinite(dir[2]);
}

bool equirectPixel(const double* k, const double dir[3], double& px, double& py) {
  const double horizontal = std::sqrt(dir[0] * dir[0] + dir[2] * dir[2]);
  if (!(horizontal + std::abs(dir[1]) > 0)) return false;
  const double theta = std::atan2(dir[0], dir[2]), phi = std::atan2(-dir[1], horizontal);
  px = (theta / (2 * kPi) + 0.5) * k[0];
  py = (0.5 - phi / kPi) * k[1];
  return std::isfinite(px) && std::isfinite(py);
}

void equirectIntrinsics(const double* k, double& fx, double& fy, double& cx, double& cy) {
  fx = k[0] / (2 * kPi), fy = k[1] / kPi, cx = k[0] / 2, cy = k[1] / 2;
}

void equirectCheck(const char* model, const double* k) {
  if (!(k[0] > 0 && k[1] > 0))
    throw Error(cat("camera model ", model, ": w = ", k[0], " and h = ", k[1],
                    " must be > 0 (the image size in pixels)"));
}

void noProfile(const double*, double, double& rho, double& drho) { rho = drho = kNaN; }

}  // namespace

const LensFormula kFovFormula{fovProfile, fovInverse, fovCheck, true};
const LensFormula kDivisionFormula{divisionProfile, divisionInverse, nullptr, true};
const LensFormula kEucmFormula{eucmProfile, eucmInverse, eucmCheck, true};
const LensFormula kRadTanThinPrismFormula{radTanProfile, nullptr,         nullptr,
                                          true,          radTanNonRadial, radTanReach};
const LensFormula kEquirectangularFormula{noProfile,   nullptr,       equirectCheck,
                                          true,        nullptr,       nullptr,
                                          equirectRay, equirectPixel, equirectIntrinsics};

}  // namespace aperture
