// COLMAP's camera models: the table, parameter access, the forward model with its analytic
// Jacobian, the inverse by Newton's method and the valid region where the inverse exists.
#include "cameras/lens_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.h"
#include "core/spelling.h"
#include "core/units.h"

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
  fx_ = params_[0], fy_ = params_[single ? 0 : 1];
  cx_ = params_[single ? 1 : 2], cy_ = params_[single ? 2 : 3];
  fisheye_ = m.fisheye;
  if (fx_ <= 0 || fy_ <= 0)
    throw Error(
        cat("camera model ", m.name, ": focal length must be > 0 (got ", fx_, ", ", fy_, ")"));
  terms_ = termsOf(model_, distortion());
  valid_ = findValidRegion();
  tabulateInverse();
}

double Lens::fx() const { return fx_; }
double Lens::fy() const { return fy_; }
double Lens::cx() const { return cx_; }
double Lens::cy() const { return cy_; }

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

// Newton's method on the 2D map (models with tangential or thin-prism terms). Residuals are in
// normalised coordinates, relative to max(1, |distorted|): iterations stop at 1e-15 (the
// rounding floor of the forward map) or when the step stalls at rounding; a solution is
// accepted up to 1e-12 (1e-6 px at a focal length of 1e6 px). From the radial inverse it takes
// three or four steps; 20 is far beyond what convergence needs away from a fold. A step that
// leaves the fold or raises the residual is halved, at most 40 times.
constexpr int kMaxNewtonIterations = 20;
constexpr int kMaxHalvings = 40;
constexpr double kConvergedResidual = 1e-15;
constexpr double kAcceptedResidual = 1e-12;
constexpr double kStalledStep = 1e-15;

// The radial profile's inverse: Newton's method inside a bracket (bisection when a step leaves
// it) from a first guess tabulated at 256 + 1 distorted radii up to 8 (normalised; 83°
// off-axis for an undistorted pinhole) or to the fold when nearer. From the table's cubic
// interpolation (good to ~1e-9) one step reaches rounding.
constexpr int kMaxRadialIterations = 100;
constexpr int kInverseTableCells = 256;
constexpr double kInverseTableEnd = 8;

// Σ c[i] sⁱ (i < n) and its derivative by s, by Horner's rule.
double polynomial(const double* c, int n, double s, double& derivative) {
  double p = c[n - 1], dp = 0;
  for (int i = n - 2; i >= 0; --i) {
    dp = dp * s + p;
    p = p * s + c[i];
  }
  derivative = dp;
  return p;
}

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
Lens::Terms Lens::termsOf(LensModelId model, const std::vector<double>& k) {
  Terms t;
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

void Lens::gain(double s, double& g, double& dg) const {
  double dn = 0;
  const double n = polynomial(terms_.num, 5, s, dn);
  if (!terms_.rational) {
    g = n, dg = dn;
    return;
  }
  double dd = 0;
  const double d = polynomial(terms_.den, 4, s, dd);
  g = n / d;
  dg = (dn * d - n * dd) / (d * d);
}

void Lens::radialProfile(double r, double& rho, double& drho) const {
  const double s = r * r;
  double g = 1, dg = 0;
  gain(s, g, dg);
  rho = r * g;
  drho = g + 2 * s * dg;
}

glm::dvec2 Lens::distort(const glm::dvec2& p, glm::dmat2* jacobian) const {
  if (terms_.identity) {
    if (jacobian) *jacobian = glm::dmat2(1.0);
    return p;
  }
  const Terms& t = terms_;
  const double u = p.x, v = p.y;
  const double uu = u * u, vv = v * v, uv = u * v, s = uu + vv;
  double g = 1, dg = 0;
  gain(s, g, dg);
  if (jacobian) {
    // Columns: the derivatives by u and by v. d(g(s)·u)/du = g + 2u²·g'(s), and so on.
    (*jacobian)[0] = glm::dvec2(g + 2 * uu * dg + 2 * t.p1 * v + 6 * t.p2 * u + 2 * t.sx1 * u,
                                2 * uv * dg + 2 * t.p2 * v + 2 * t.p1 * u + 2 * t.sy1 * u);
    (*jacobian)[1] = glm::dvec2(2 * uv * dg + 2 * t.p1 * u + 2 * t.p2 * v + 2 * t.sx1 * v,
                                g + 2 * vv * dg + 2 * t.p2 * u + 6 * t.p1 * v + 2 * t.sy1 * v);
  }
  return {g * u + 2 * t.p1 * uv + t.p2 * (s + 2 * uu) + t.sx1 * s,
          g * v + 2 * t.p2 * uv + t.p1 * (s + 2 * vv) + t.sy1 * s};
}

// The map is invertible along a radius while ρ(r) = r·g(r²) increases (ρ' > 0) and, for the
// rational FULL_OPENCV, before the first pole of g (D(r²) > 0): the valid region ends at the
// first r where either fails. ρ'(0) = 1 and D(0) = 1 for every model.
LensValidRegion Lens::findValidRegion() const {
  const bool fisheye = info().fisheye;
  LensValidRegion region;
  region.maxUndistorted = region.maxDistorted = fisheye ? kPi : kInf;
  if (terms_.identity) return region;

  const auto invertible = [this](double r) {
    if (terms_.rational) {
      double dd = 0;
      if (!(polynomial(terms_.den, 4, r * r, dd) > 0)) return false;
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
  inverseRadius_.clear(), inverseSlope_.clear();
  if (terms_.identity) return;
  const double end = std::min(kInverseTableEnd, valid_.maxDistorted * (1 - 1e-6));
  std::vector<double> radius(kInverseTableCells + 1), slope(kInverseTableCells + 1);
  for (int k = 0; k <= kInverseTableCells; ++k) {
    const std::optional<double> r = invertRadialProfile(end * k / kInverseTableCells);
    if (!r) return;  // cannot happen below maxDistorted; without a table, Newton starts at t
    double rho = 0, drho = 0;
    radialProfile(*r, rho, drho);
    radius[k] = *r, slope[k] = 1 / drho;
  }
  inverseStep_ = end / kInverseTableCells;
  inverseRadius_ = std::move(radius), inverseSlope_ = std::move(slope);
}

std::optional<double> Lens::invertRadialProfile(double t, bool exact) const {
  if (!(t >= 0)) return std::nullopt;
  if (t == 0) return 0.0;
  if (valid_.bounded() && !(t < valid_.maxDistorted)) return std::nullopt;
  // The bracket [lo, hi] (ρ(lo) <= t <= ρ(hi)) and the first guess: the table's cell of t with
  // cubic Hermite interpolation (good to ~1e-9: one Newton step then reaches rounding), past
  // the table from its end to the fold, or by doubling where nothing bounds r.
  double lo = 0, hi = 0, r = t, rho = 0, drho = 0;
  const double cell = inverseRadius_.empty() ? kInf : t / inverseStep_;
  if (cell < kInverseTableCells) {
    const int k = static_cast<int>(cell);
    const double s = cell - k, h = inverseStep_;
    lo = inverseRadius_[k], hi = inverseRadius_[k + 1];
    r = (1 + 2 * s) * (1 - s) * (1 - s) * lo + s * (1 - s) * (1 - s) * h * inverseSlope_[k] +
        s * s * (3 - 2 * s) * hi + s * s * (s - 1) * h * inverseSlope_[k + 1];
    if (!exact) return std::min(std::max(r, lo), hi);
  } else {
    lo = inverseRadius_.empty() ? 0 : inverseRadius_.back();
    if (valid_.bounded()) {
      hi = valid_.maxUndistorted;
    } else {
      for (hi = std::max({1.0, t, 2 * lo});; hi *= 2) {
        radialProfile(hi, rho, drho);
        if (!(rho < t)) break;
        if (hi > 1e300) return std::nullopt;
      }
    }
  }
  // Newton on ρ(r) = t, kept inside the bracket by bisection.
  if (!(r > lo && r < hi)) r = 0.5 * (lo + hi);
  for (int i = 0; i < kMaxRadialIterations; ++i) {
    radialProfile(r, rho, drho);
    const double f = rho - t;
    if (f == 0) return drho > 0 ? std::optional<double>(r) : std::nullopt;
    (f < 0 ? lo : hi) = r;
    double next = r - f / drho;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - r) <= 1e-15 * r) {
      if (!(std::abs(f) <= kAcceptedResidual * std::max(1.0, t)) || !(drho > 0))
        return std::nullopt;
      return next;
    }
    r = next;
  }
  return std::nullopt;
}

std::optional<glm::dvec2> Lens::newton(const glm::dvec2& target, glm::dvec2 x) const {
  const double scale = std::max(1.0, glm::length(target));
  glm::dmat2 jacobian;
  glm::dvec2 residual = distort(x, &jacobian) - target;
  double error = glm::length(residual);
  bool stalled = false;
  for (int i = 0;; ++i) {
    const double det = glm::determinant(jacobian);
    if (!std::isfinite(error) || !std::isfinite(det) || det == 0) return std::nullopt;
    if (error <= kConvergedResidual * scale || (stalled && error <= kAcceptedResidual * scale)) {
      // A solution on the folded side of the map (det < 0) or past the radial fold is not the
      // inverse: no ray.
      if (!(det > 0) || !(glm::length(x) < valid_.maxUndistorted)) return std::nullopt;
      return x;
    }
    if (stalled || i == kMaxNewtonIterations) return std::nullopt;
    // step = J⁻¹ · residual, written out for the 2 × 2 case; halved until the new point stays
    // inside the radial fold and does not raise the residual (near a fold the full step can
    // overshoot onto the other side). No decrease in kMaxHalvings: the residual is at its floor.
    glm::dvec2 step((jacobian[1][1] * residual.x - jacobian[1][0] * residual.y) / det,
                    (-jacobian[0][1] * residual.x + jacobian[0][0] * residual.y) / det);
    stalled = true;
    for (int h = 0; h < kMaxHalvings; ++h, step *= 0.5) {
      const glm::dvec2 next = x - step;
      if (!(glm::length(next) < valid_.maxUndistorted)) continue;
      glm::dmat2 nextJacobian;
      const glm::dvec2 nextResidual = distort(next, &nextJacobian) - target;
      const double nextError = glm::length(nextResidual);
      if (!(nextError <= error)) continue;
      stalled = glm::length(step) <= kStalledStep * std::max(1.0, glm::length(next));
      x = next, jacobian = nextJacobian, residual = nextResidual, error = nextError;
      break;
    }
  }
}

// Inside the fold (s <= R²) the tangential terms move a point by at most
// |2 p1 u v + p2 (s + 2u²)| + |2 p2 u v + p1 (s + 2v²)| <= 4 (|p1| + |p2|) s and the thin prism
// by |(sx1, sy1)| s, while the radial part stays within maxDistorted: a distorted point farther
// out than their sum has no preimage in the valid region.
double Lens::nonRadialReach() const {
  const double s = valid_.maxUndistorted * valid_.maxUndistorted;
  return (4 * (std::abs(terms_.p1) + std::abs(terms_.p2)) + std::hypot(terms_.sx1, terms_.sy1)) * s;
}

std::optional<glm::dvec2> Lens::undistort(const glm::dvec2& distorted) const {
  if (!isFinite(distorted)) return std::nullopt;
  const double t = glm::length(distorted);
  if (terms_.identity) {
    if (!(t < valid_.maxUndistorted)) return std::nullopt;  // a fisheye's θ >= π
    return distorted;
  }
  if (t == 0) return glm::dvec2(0.0);  // every model maps 0 to 0 with the identity Jacobian
  const std::optional<double> r = invertRadialProfile(t, terms_.radialOnly);
  // Radial models: (u', v') = (ρ(r)/r)·(u, v) points along (u, v), so the radial inverse is the
  // whole inverse, with the same residual, and ρ' > 0, ρ > 0 inside the fold make the
  // Jacobian's determinant (ρ/r)·ρ' positive.
  if (terms_.radialOnly) {
    if (!r) return std::nullopt;
    return distorted * (*r / t);
  }
  // With tangential or thin-prism terms, Newton on the 2D map starts from the radial inverse
  // along the point's own direction; when the radial part alone has no inverse there, just
  // inside the fold, unless the point lies beyond the terms' reach.
  glm::dvec2 start(0.0);
  if (r)
    start = distorted * (*r / t);
  else if (valid_.bounded() && t < valid_.maxDistorted + nonRadialReach())
    start = distorted * (0.99 * valid_.maxUndistorted / t);
  else
    return std::nullopt;
  return newton(distorted, start);
}

std::optional<glm::dvec2> Lens::project(const glm::dvec3& dir) const {
  if (!std::isfinite(dir.x) || !std::isfinite(dir.y) || !std::isfinite(dir.z)) return std::nullopt;
  glm::dvec2 undistorted(0.0);
  if (fisheye_) {
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
  const glm::dvec2 d = distort(undistorted, terms_.radialOnly ? nullptr : &jacobian);
  if (!(glm::determinant(jacobian) > 0)) return std::nullopt;
  const glm::dvec2 pixel(fx_ * d.x + cx_, fy_ * d.y + cy_);
  if (!isFinite(pixel)) return std::nullopt;
  return pixel;
}

std::optional<glm::dvec3> Lens::unproject(const glm::dvec2& pixel) const {
  const glm::dvec2 distorted((pixel.x - cx_) / fx_, (pixel.y - cy_) / fy_);
  const std::optional<glm::dvec2> u = undistort(distorted);
  if (!u) return std::nullopt;
  if (fisheye_) {
    // (u, v) = θ·(x, y)/|(x, y)|: the ray at θ off-axis along the azimuth of (u, v).
    const double theta = glm::length(*u);
    if (theta == 0) return glm::dvec3(0, 0, 1);
    const double s = std::sin(theta) / theta;
    return glm::dvec3(u->x * s, u->y * s, std::cos(theta));
  }
  return glm::normalize(glm::dvec3(u->x, u->y, 1.0));
}

}  // namespace aperture
