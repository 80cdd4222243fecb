// COLMAP's camera models: the table, parameter access, the forward model with its analytic
// Jacobian, the inverse by Newton's method and the valid region where the inverse exists.
#include "cameras/lenses/lens_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/util/error.h"
#include "core/util/spelling.h"
#include "core/util/units.h"

namespace aperture {

const std::vector<LensModelInfo>& lensModels() {
  static const std::vector<LensModelInfo> models = {
      {LensModelId::SimplePinhole, "SIMPLE_PINHOLE", 0, {"f", "cx", "cy"}, false},
      {LensModelId::Pinhole, "PINHOLE", 1, {"fx", "fy", "cx", "cy"}, false},
      {LensModelId::SimpleRadial, "SIMPLE_RADIAL", 2, {"f", "cx", "cy", "k"}, false},
      {LensModelId::Radial, "RADIAL", 3, {"f", "cx", "cy", "k1", "k2"}, false},
      {LensModelId::OpenCV, "OPENCV", 4, {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"}, false},
      {LensModelId::OpenCVFisheye,
       "OPENCV_FISHEYE",
       5,
       {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"},
       true},
      {LensModelId::FullOpenCV,
       "FULL_OPENCV",
       6,
       {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"},
       false},
      {LensModelId::SimpleRadialFisheye, "SIMPLE_RADIAL_FISHEYE", 8, {"f", "cx", "cy", "k"}, true},
      {LensModelId::RadialFisheye, "RADIAL_FISHEYE", 9, {"f", "cx", "cy", "k1", "k2"}, true},
      {LensModelId::ThinPrismFisheye,
       "THIN_PRISM_FISHEYE",
       10,
       {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "sx1", "sy1"},
       true},
  };
  return models;
}

const LensModelInfo& lensModelInfo(LensModelId id) {
  for (const LensModelInfo& m : lensModels())
    if (m.id == id) return m;
  throw Error("internal: unknown lens model id");
}

const LensModelInfo& findLensModel(const std::string& name) {
  std::string upper = name;
  for (char& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
  std::vector<std::string> names;
  for (const LensModelInfo& m : lensModels()) {
    if (upper == m.name) return m;
    names.emplace_back(m.name);
  }
  throw Error(cat("unsupported camera model '", name, "' (supported: ", join(names, ", "), ")",
                  didYouMean(upper, names)));
}

const LensModelInfo* findLensModelByColmapId(int colmapId) {
  for (const LensModelInfo& m : lensModels())
    if (m.colmapId == colmapId) return &m;
  return nullptr;
}

Lens::Lens(LensModelId model, std::vector<double> params)
    : model_(model), params_(std::move(params)) {
  const LensModelInfo& m = info();
  if (params_.size() != m.paramNames.size())
    throw Error(cat("camera model ", m.name, " takes ", m.paramNames.size(), " parameters (",
                    join(m.paramNames, " "), "), got ", params_.size()));
  for (size_t i = 0; i < params_.size(); ++i)
    if (!std::isfinite(params_[i]))
      throw Error(cat("camera model ", m.name, ": parameter ", m.paramNames[i], " is ", params_[i],
                      " (must be finite)"));
  const bool single = m.singleFocal();
  LensInverse& c = inverse_;
  c.fx = params_[0], c.fy = params_[single ? 0 : 1];
  c.cx = params_[single ? 1 : 2], c.cy = params_[single ? 2 : 3];
  c.fisheye = m.fisheye;
  if (c.fx <= 0 || c.fy <= 0)
    throw Error(
        cat("camera model ", m.name, ": focal length must be > 0 (got ", c.fx, ", ", c.fy, ")"));
  c.terms = termsOf(model_, distortion());
  valid_ = findValidRegion();
  c.bounded = valid_.bounded();
  c.maxUndistorted = valid_.maxUndistorted;
  c.maxDistorted = valid_.maxDistorted;
  c.nonRadialLimit =
      c.bounded ? valid_.maxDistorted + nonRadialReach() : std::numeric_limits<double>::infinity();
  tabulateInverse();
}

double Lens::fx() const { return inverse_.fx; }
double Lens::fy() const { return inverse_.fy; }
double Lens::cx() const { return inverse_.cx; }
double Lens::cy() const { return inverse_.cy; }

std::vector<double> Lens::distortion() const {
  return {params_.begin() + (info().singleFocal() ? 3 : 4), params_.end()};
}

bool Lens::distorted() const {
  if (info().fisheye) return true;
  for (double k : distortion())
    if (k != 0) return true;
  return false;
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The valid region is found by scanning the undistorted radius (r or θ) in geometric steps of
// 0.5% from 1e-4 to the end (π for the fisheyes; r = 1e6, 89.99994° off-axis, for the others:
// no fold found by then means none), then bisecting the first failing step to the last bit.
// A fold narrower than one step (ρ' dipping below zero and back within 0.5%) can be missed;
// the inverse still refuses every point on the folded part, by the sign of ρ' (radial models)
// or of the Jacobian's determinant.
constexpr double kScanStart = 1e-4;
constexpr double kScanRatio = 1.005;
constexpr double kPinholeScanEnd = 1e6;

// The radial profile's inverse starts from a first guess tabulated at 256 + 1 distorted radii
// up to 8 (normalised; 83° off-axis for an undistorted pinhole) or to the fold when nearer
// (cameras/lenses/lens_inverse.cpp refines it).
constexpr int kInverseTableCells = 256;
constexpr double kInverseTableEnd = 8;

bool isFinite(const glm::dvec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }

}  // namespace

bool LensValidRegion::bounded() const { return std::isfinite(maxUndistorted); }

std::string LensValidRegion::text(bool fisheye) const {
  if (!bounded()) return "unbounded";
  const double offAxis = fisheye ? maxUndistorted : std::atan(maxUndistorted);
  char s[160];
  std::snprintf(s, sizeof s, "%s < %.4g%s (distorted %.4g, %.1f° off-axis)", fisheye ? "θ" : "r",
                maxUndistorted, fisheye ? " rad" : "", maxDistorted, offAxis * kDegPerRad);
  return s;
}

// The coefficients come in COLMAP's order (models.h, the models' Distortion functions).
DistortionTerms Lens::termsOf(LensModelId model, const std::vector<double>& k) {
  DistortionTerms t;
  switch (model) {
    case LensModelId::SimplePinhole:
    case LensModelId::Pinhole:
      break;
    case LensModelId::SimpleRadial:  // k
    case LensModelId::SimpleRadialFisheye:
      t.num[1] = k[0];
      break;
    case LensModelId::Radial:  // k1, k2
    case LensModelId::RadialFisheye:
      t.num[1] = k[0], t.num[2] = k[1];
      break;
    case LensModelId::OpenCV:  // k1, k2, p1, p2
      t.num[1] = k[0], t.num[2] = k[1], t.p1 = k[2], t.p2 = k[3];
      break;
    case LensModelId::FullOpenCV:  // k1, k2, p1, p2, k3, k4, k5, k6
      t.num[1] = k[0], t.num[2] = k[1], t.p1 = k[2], t.p2 = k[3], t.num[3] = k[4];
      t.den[1] = k[5], t.den[2] = k[6], t.den[3] = k[7];
      break;
    case LensModelId::OpenCVFisheye:  // k1, k2, k3, k4
      t.num[1] = k[0], t.num[2] = k[1], t.num[3] = k[2], t.num[4] = k[3];
      break;
    case LensModelId::ThinPrismFisheye:  // k1, k2, p1, p2, k3, k4, sx1, sy1
      t.num[1] = k[0], t.num[2] = k[1], t.p1 = k[2], t.p2 = k[3], t.num[3] = k[4];
      t.num[4] = k[5], t.sx1 = k[6], t.sy1 = k[7];
      break;
  }
  t.rational = t.den[1] != 0 || t.den[2] != 0 || t.den[3] != 0;
  t.radialOnly = t.p1 == 0 && t.p2 == 0 && t.sx1 == 0 && t.sy1 == 0;
  t.identity = t.radialOnly && !t.rational && t.num[1] == 0 && t.num[2] == 0 && t.num[3] == 0 &&
               t.num[4] == 0;
  return t;
}

glm::dvec2 Lens::distort(const glm::dvec2& p, glm::dmat2* jacobian) const {
  if (inverse_.terms.identity) {
    if (jacobian) *jacobian = glm::dmat2(1.0);
    return p;
  }
  glm::dvec2 d;
  double j[4] = {};
  distortPoint(inverse_.terms, p.x, p.y, d.x, d.y, jacobian != nullptr, j);
  if (jacobian) *jacobian = glm::dmat2(j[0], j[1], j[2], j[3]);  // column by column
  return d;
}

// The map is invertible along a radius while ρ(r) = r·g(r²) increases (ρ' > 0) and, for the
// rational FULL_OPENCV, before the first pole of g (D(r²) > 0): the valid region ends at the
// first r where either fails. ρ'(0) = 1 and D(0) = 1 for every model.
LensValidRegion Lens::findValidRegion() const {
  const bool fisheye = info().fisheye;
  LensValidRegion region;
  region.maxUndistorted = region.maxDistorted = fisheye ? kPi : kInf;
  if (inverse_.terms.identity) return region;

  const auto invertible = [this](double r) {
    if (inverse_.terms.rational) {
      double dd = 0;
      if (!(polynomialAt<4>(inverse_.terms.den, r * r, dd) > 0)) return false;
    }
    double rho = 0, drho = 0;
    radialProfile(r, rho, drho);
    return drho > 0 && std::isfinite(rho);
  };
  const double scanEnd = fisheye ? kPi : kPinholeScanEnd;
  double lo = 0, hi = kScanStart;
  while (invertible(hi)) {
    if (hi >= scanEnd) {
      double drho = 0;
      if (fisheye) radialProfile(kPi, region.maxDistorted, drho);
      return region;
    }
    lo = hi;
    hi = std::min(hi * kScanRatio, scanEnd);
  }
  for (;;) {
    const double mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    (invertible(mid) ? lo : hi) = mid;
  }
  double drho = 0;
  region.maxUndistorted = lo;
  radialProfile(lo, region.maxDistorted, drho);
  return region;
}

void Lens::tabulateInverse() {
  inverse_.inverseRadius.clear(), inverse_.inverseSlope.clear();  // none while it is made
  if (inverse_.terms.identity) return;
  const double end = std::min(kInverseTableEnd, valid_.maxDistorted * (1 - 1e-6));
  std::vector<double> radius(kInverseTableCells + 1), slope(kInverseTableCells + 1);
  for (int k = 0; k <= kInverseTableCells; ++k) {
    const std::optional<double> r = invertRadialProfile(end * k / kInverseTableCells);
    if (!r) return;  // cannot happen below maxDistorted; without a table, Newton starts at t
    double rho = 0, drho = 0;
    radialProfile(*r, rho, drho);
    radius[k] = *r, slope[k] = 1 / drho;
  }
  inverse_.step = end / kInverseTableCells;
  inverse_.inverseRadius = std::move(radius), inverse_.inverseSlope = std::move(slope);
}

std::optional<double> Lens::invertRadialProfile(double t, bool exact) const {
  double r = 0;
  if (!invertRadialOne(inverse_, t, exact, r)) return std::nullopt;
  return r;
}

// Inside the fold (s <= R²) the tangential terms move a point by at most
// |2 p1 u v + p2 (s + 2u²)| + |2 p2 u v + p1 (s + 2v²)| <= 4 (|p1| + |p2|) s and the thin prism
// by |(sx1, sy1)| s, while the radial part stays within maxDistorted: a distorted point farther
// out than their sum has no preimage in the valid region.
double Lens::nonRadialReach() const {
  const double s = valid_.maxUndistorted * valid_.maxUndistorted;
  return (4 * (std::abs(inverse_.terms.p1) + std::abs(inverse_.terms.p2)) +
          std::hypot(inverse_.terms.sx1, inverse_.terms.sy1)) *
         s;
}

std::optional<glm::dvec2> Lens::undistort(const glm::dvec2& distorted) const {
  glm::dvec2 u;
  if (!undistortOne(inverse_, distorted.x, distorted.y, u.x, u.y)) return std::nullopt;
  return u;
}

std::optional<glm::dvec2> Lens::project(const glm::dvec3& dir) const {
  if (!std::isfinite(dir.x) || !std::isfinite(dir.y) || !std::isfinite(dir.z)) return std::nullopt;
  glm::dvec2 undistorted(0.0);
  if (inverse_.fisheye) {
    // θ from atan2, not atan(r/z): the fisheyes see beyond 90° off-axis.
    const double rxy = std::hypot(dir.x, dir.y);
    if (rxy == 0 && !(dir.z > 0)) return std::nullopt;  // the zero vector, or straight back
    const double theta = std::atan2(rxy, dir.z);
    if (!(theta < valid_.maxUndistorted)) return std::nullopt;
    if (rxy > 0) undistorted = glm::dvec2(dir.x, dir.y) * (theta / rxy);
  } else {
    if (!(dir.z > 0)) return std::nullopt;
    undistorted = glm::dvec2(dir.x / dir.z, dir.y / dir.z);
    if (!(glm::length(undistorted) < valid_.maxUndistorted)) return std::nullopt;
  }
  // With tangential or thin-prism terms the map can fold in 2D inside the radial region:
  // project only where unproject would return the direction.
  glm::dmat2 jacobian(1.0);
  const glm::dvec2 d = distort(undistorted, inverse_.terms.radialOnly ? nullptr : &jacobian);
  if (!(glm::determinant(jacobian) > 0)) return std::nullopt;
  const glm::dvec2 pixel(fx() * d.x + cx(), fy() * d.y + cy());
  if (!isFinite(pixel)) return std::nullopt;
  return pixel;
}

std::optional<glm::dvec3> Lens::unproject(const glm::dvec2& pixel) const {
  double dir[3];
  if (!unprojectOne(inverse_, pixel.x, pixel.y, dir)) return std::nullopt;
  return glm::dvec3(dir[0], dir[1], dir[2]);
}

void Lens::unprojectBatch(int n, const glm::dvec2* pixels, glm::dvec3* dirs, bool* hasRay) const {
  const LensInverse& c = inverse_;
  if (n == 1) {  // one lane, not eight with seven idle
    double dir[3];
    hasRay[0] = unprojectOne(c, pixels[0].x, pixels[0].y, dir);
    dirs[0] = glm::dvec3(dir[0], dir[1], dir[2]);
    return;
  }
  double px[kBatch], py[kBatch], dx[kBatch], dy[kBatch], dz[kBatch];
  bool solve[kBatch];
  for (int k = 0; k < kBatch; ++k) {
    solve[k] = k < n;
    px[k] = solve[k] ? pixels[k].x : 0.0, py[k] = solve[k] ? pixels[k].y : 0.0;
  }
  unprojectEight(c, px, py, dx, dy, dz, solve);
  for (int k = 0; k < n; ++k) dirs[k] = glm::dvec3(dx[k], dy[k], dz[k]), hasRay[k] = solve[k];
}

}  // namespace aperture
