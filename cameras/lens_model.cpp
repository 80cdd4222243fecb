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

std::optional<double> Lens::radialBracketEnd(double t, double lo) const {
  double rho = 0, drho = 0;
  for (double hi = std::max({1.0, t, 2 * lo});; hi *= 2) {
    radialProfile(hi, rho, drho);
    if (!(rho < t)) return hi;
    if (hi > 1e300) return std::nullopt;
  }
}

template <int L>
__attribute__((flatten)) void Lens::invertRadialLanes(const double* t, bool exact, double* r,
                                                      bool* solve) const {
  // Each lane's bracket [lo, hi] (ρ(lo) <= t <= ρ(hi)) and first guess: the table's cell of t
  // with cubic Hermite interpolation (good to ~1e-9: one Newton step then reaches rounding),
  // past the table from its end to the fold, or by doubling where nothing bounds r.
  double lo[L], hi[L];
  bool running[L];
  for (int k = 0; k < L; ++k) {
    running[k] = false;
    if (!solve[k]) continue;
    solve[k] = false;
    const double tk = t[k];
    if (!(tk >= 0)) continue;
    if (tk == 0) {
      r[k] = 0, solve[k] = true;
      continue;
    }
    if (valid_.bounded() && !(tk < valid_.maxDistorted)) continue;
    double l = 0, h = 0, guess = tk;
    const double cell = inverseRadius_.empty() ? kInf : tk / inverseStep_;
    if (cell < kInverseTableCells) {
      const int c = static_cast<int>(cell);
      const double s = cell - c, w = inverseStep_;
      l = inverseRadius_[c], h = inverseRadius_[c + 1];
      guess = (1 + 2 * s) * (1 - s) * (1 - s) * l + s * (1 - s) * (1 - s) * w * inverseSlope_[c] +
              s * s * (3 - 2 * s) * h + s * s * (s - 1) * w * inverseSlope_[c + 1];
      if (!exact) {
        r[k] = std::min(std::max(guess, l), h), solve[k] = true;
        continue;
      }
    } else {
      l = inverseRadius_.empty() ? 0 : inverseRadius_.back();
      if (valid_.bounded()) {
        h = valid_.maxUndistorted;
      } else {
        const std::optional<double> end = radialBracketEnd(tk, l);
        if (!end) continue;
        h = *end;
      }
    }
    if (!(guess > l && guess < h)) guess = 0.5 * (l + h);
    lo[k] = l, hi[k] = h, r[k] = guess, running[k] = true;
  }
  // Newton on ρ(r) = t, kept inside the bracket by bisection, every running lane one step per
  // round.
  for (int i = 0; i < kMaxRadialIterations; ++i) {
    bool any = false;
    for (int k = 0; k < L; ++k) {
      if (!running[k]) continue;
      double rho = 0, drho = 0;
      radialProfile(r[k], rho, drho);
      const double f = rho - t[k];
      if (f == 0) {
        solve[k] = drho > 0, running[k] = false;
        continue;
      }
      (f < 0 ? lo[k] : hi[k]) = r[k];
      double next = r[k] - f / drho;
      if (!(next > lo[k] && next < hi[k])) next = 0.5 * (lo[k] + hi[k]);
      if (std::abs(next - r[k]) <= 1e-15 * r[k]) {
        solve[k] = std::abs(f) <= kAcceptedResidual * std::max(1.0, t[k]) && drho > 0;
        r[k] = next, running[k] = false;
        continue;
      }
      r[k] = next, any = true;
    }
    if (!any) break;
  }
}

std::optional<double> Lens::invertRadialProfile(double t, bool exact) const {
  double r = 0;
  bool solved = true;
  invertRadialLanes<1>(&t, exact, &r, &solved);
  return solved ? std::optional<double>(r) : std::nullopt;
}

template <int L>
__attribute__((flatten)) void Lens::newtonLanes(const glm::dvec2* target, glm::dvec2* x,
                                                bool* solve) const {
  double scale[L] = {}, error[L] = {};
  glm::dmat2 jacobian[L] = {};
  glm::dvec2 residual[L] = {}, step[L] = {};
  bool running[L], stalled[L], searching[L];
  for (int k = 0; k < L; ++k) {
    running[k] = solve[k], solve[k] = false, stalled[k] = false;
    if (!running[k]) continue;
    scale[k] = std::max(1.0, glm::length(target[k]));
    residual[k] = distort(x[k], &jacobian[k]) - target[k];
    error[k] = glm::length(residual[k]);
  }
  for (int i = 0;; ++i) {
    bool any = false;
    for (int k = 0; k < L; ++k) {
      searching[k] = false;
      if (!running[k]) continue;
      const glm::dmat2& J = jacobian[k];
      const double det = glm::determinant(J);
      if (!std::isfinite(error[k]) || !std::isfinite(det) || det == 0) {
        running[k] = false;
        continue;
      }
      if (error[k] <= kConvergedResidual * scale[k] ||
          (stalled[k] && error[k] <= kAcceptedResidual * scale[k])) {
        // A solution on the folded side of the map (det < 0) or past the radial fold is not
        // the inverse: no ray.
        solve[k] = det > 0 && glm::length(x[k]) < valid_.maxUndistorted, running[k] = false;
        continue;
      }
      if (stalled[k] || i == kMaxNewtonIterations) {
        running[k] = false;
        continue;
      }
      // step = J⁻¹ · residual, written out for the 2 × 2 case.
      const glm::dvec2& e = residual[k];
      step[k] =
          glm::dvec2((J[1][1] * e.x - J[1][0] * e.y) / det, (-J[0][1] * e.x + J[0][0] * e.y) / det);
      stalled[k] = true, searching[k] = true, any = true;
    }
    if (!any) return;
    // Each step is halved until the new point stays inside the radial fold and does not raise
    // the residual (near a fold the full step can overshoot onto the other side). No decrease
    // in kMaxHalvings: the residual is at its floor, and the lane stays stalled.
    for (int h = 0; h < kMaxHalvings; ++h) {
      bool more = false;
      for (int k = 0; k < L; ++k) {
        if (!searching[k]) continue;
        const glm::dvec2 next = x[k] - step[k];
        if (glm::length(next) < valid_.maxUndistorted) {
          glm::dmat2 nextJacobian;
          const glm::dvec2 nextResidual = distort(next, &nextJacobian) - target[k];
          const double nextError = glm::length(nextResidual);
          if (nextError <= error[k]) {
            stalled[k] = glm::length(step[k]) <= kStalledStep * std::max(1.0, glm::length(next));
            x[k] = next, jacobian[k] = nextJacobian, residual[k] = nextResidual;
            error[k] = nextError, searching[k] = false;
            continue;
          }
        }
        step[k] *= 0.5, more = true;
      }
      if (!more) break;
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

template <int L>
__attribute__((flatten)) void Lens::undistortLanes(const glm::dvec2* distorted,
                                                   glm::dvec2* undistorted, bool* solve) const {
  double t[L];
  for (int k = 0; k < L; ++k) {
    if (solve[k] && !isFinite(distorted[k])) solve[k] = false;
    t[k] = solve[k] ? glm::length(distorted[k]) : 0.0;
  }
  if (terms_.identity) {
    for (int k = 0; k < L; ++k) {
      if (!solve[k]) continue;
      solve[k] = t[k] < valid_.maxUndistorted;  // a fisheye's θ >= π has none
      undistorted[k] = distorted[k];
    }
    return;
  }
  // Every model maps 0 to 0 with the identity Jacobian: t = 0 needs no inverse.
  double r[L] = {};
  bool radial[L];
  for (int k = 0; k < L; ++k) {
    radial[k] = solve[k] && t[k] != 0;
    if (solve[k] && t[k] == 0) undistorted[k] = glm::dvec2(0.0);
  }
  invertRadialLanes<L>(t, terms_.radialOnly, r, radial);
  // Radial models: (u', v') = (ρ(r)/r)·(u, v) points along (u, v), so the radial inverse is the
  // whole inverse, with the same residual, and ρ' > 0, ρ > 0 inside the fold make the
  // Jacobian's determinant (ρ/r)·ρ' positive.
  if (terms_.radialOnly) {
    for (int k = 0; k < L; ++k) {
      if (!solve[k] || t[k] == 0) continue;
      solve[k] = radial[k];
      if (radial[k]) undistorted[k] = distorted[k] * (r[k] / t[k]);
    }
    return;
  }
  // With tangential or thin-prism terms, Newton on the 2D map starts from the radial inverse
  // along the point's own direction; when the radial part alone has no inverse there, just
  // inside the fold, unless the point lies beyond the terms' reach.
  const double reach = valid_.bounded() ? valid_.maxDistorted + nonRadialReach() : kInf;
  bool newton[L];
  for (int k = 0; k < L; ++k) {
    newton[k] = false;
    if (!solve[k] || t[k] == 0) continue;
    if (radial[k]) {
      undistorted[k] = distorted[k] * (r[k] / t[k]);
    } else if (valid_.bounded() && t[k] < reach) {
      undistorted[k] = distorted[k] * (0.99 * valid_.maxUndistorted / t[k]);
    } else {
      solve[k] = false;
      continue;
    }
    newton[k] = true;
  }
  newtonLanes<L>(distorted, undistorted, newton);
  for (int k = 0; k < L; ++k)
    if (solve[k] && t[k] != 0) solve[k] = newton[k];
}

std::optional<glm::dvec2> Lens::undistort(const glm::dvec2& distorted) const {
  glm::dvec2 undistorted(0.0);
  bool solved = true;
  undistortLanes<1>(&distorted, &undistorted, &solved);
  return solved ? std::optional<glm::dvec2>(undistorted) : std::nullopt;
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

template <int L>
__attribute__((flatten)) void Lens::unprojectLanes(const glm::dvec2* pixels, glm::dvec3* dirs,
                                                   bool* solve) const {
  glm::dvec2 distorted[L], u[L] = {};
  for (int k = 0; k < L; ++k)
    distorted[k] = glm::dvec2((pixels[k].x - cx_) / fx_, (pixels[k].y - cy_) / fy_);
  undistortLanes<L>(distorted, u, solve);
  for (int k = 0; k < L; ++k) {
    if (!solve[k]) continue;
    if (!fisheye_) {
      dirs[k] = glm::normalize(glm::dvec3(u[k].x, u[k].y, 1.0));
      continue;
    }
    // (u, v) = θ·(x, y)/|(x, y)|: the ray at θ off-axis along the azimuth of (u, v).
    const double theta = glm::length(u[k]);
    if (theta == 0) {
      dirs[k] = glm::dvec3(0, 0, 1);
      continue;
    }
    const double s = std::sin(theta) / theta;
    dirs[k] = glm::dvec3(u[k].x * s, u[k].y * s, std::cos(theta));
  }
}

std::optional<glm::dvec3> Lens::unproject(const glm::dvec2& pixel) const {
  glm::dvec3 dir(0.0);
  bool solved = true;
  unprojectLanes<1>(&pixel, &dir, &solved);
  return solved ? std::optional<glm::dvec3>(dir) : std::nullopt;
}

void Lens::unprojectBatch(int n, const glm::dvec2* pixels, glm::dvec3* dirs, bool* hasRay) const {
  if (n == 1) {  // nothing to interleave: one lane, not eight with seven idle
    hasRay[0] = true;
    return unprojectLanes<1>(pixels, dirs, hasRay);
  }
  glm::dvec2 lanePixels[kBatch];
  glm::dvec3 laneDirs[kBatch];
  bool solve[kBatch];
  for (int k = 0; k < kBatch; ++k) {
    solve[k] = k < n;
    lanePixels[k] = solve[k] ? pixels[k] : glm::dvec2(0.0);
  }
  unprojectLanes<kBatch>(lanePixels, laneDirs, solve);
  for (int k = 0; k < n; ++k) dirs[k] = laneDirs[k], hasRay[k] = solve[k];
}

}  // namespace aperture
