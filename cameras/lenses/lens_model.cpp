// COLMAP's camera models: the table, parameter access, the forward model with its analytic
// Jacobian, the inverse by Newton's method and the valid region where the inverse exists.
#include "cameras/lenses/lens_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "cameras/lenses/lens_formulas.h"
#include "core/util/error.h"
#include "core/util/spelling.h"
#include "core/util/units.h"

namespace aperture {

namespace {

// The formulas of the shared polynomial form (cameras/lens_inverse.h): each model's
// coefficients, in COLMAP's order (models.h, the models' Distortion functions), as its terms.
DistortionTerms noTerms(const double*) { return {}; }
DistortionTerms oneRadialTerm(const double* k) {  // k
  DistortionTerms t;
  t.num[1] = k[0];
  return t;
}
DistortionTerms twoRadialTerms(const double* k) {  // k1, k2
  DistortionTerms t;
  t.num[1] = k[0], t.num[2] = k[1];
  return t;
}
DistortionTerms openCVTerms(const double* k) {  // k1, k2, p1, p2
  DistortionTerms t;
  t.num[1] = k[0], t.num[2] = k[1], t.p1 = k[2], t.p2 = k[3];
  return t;
}
DistortionTerms fullOpenCVTerms(const double* k) {  // k1, k2, p1, p2, k3, k4, k5, k6
  DistortionTerms t = openCVTerms(k);
  t.num[3] = k[4];
  t.den[1] = k[5], t.den[2] = k[6], t.den[3] = k[7];
  return t;
}
DistortionTerms openCVFisheyeTerms(const double* k) {  // k1, k2, k3, k4
  DistortionTerms t;
  t.num[1] = k[0], t.num[2] = k[1], t.num[3] = k[2], t.num[4] = k[3];
  return t;
}
DistortionTerms thinPrismTerms(const double* k) {  // k1, k2, p1, p2, k3, k4, sx1, sy1
  DistortionTerms t = openCVTerms(k);
  t.num[3] = k[4], t.num[4] = k[5], t.sx1 = k[6], t.sy1 = k[7];
  return t;
}

// Spellings. OpenCV's standard model has COLMAP's OPENCV and FULL_OPENCV order (k1 k2 p1 p2
// k3 k4 k5 k6); the radial models are it with the missing coefficients zero. cv::fisheye is
// OPENCV_FISHEYE (θd = θ(1 + k1θ² + k2θ⁴ + …)); the radial fisheyes are it with the missing
// coefficients zero. nerfstudio's slots are k1 k2 k3 k4 p1 p2 (camera_utils.py: the radial
// polynomial in r² up to r⁸ and OpenCV's tangential terms; OPENCV_FISHEYE: k1..k4 in θ).
const LensSpelling kNone{};
LensSpelling openCV(std::vector<int> slots) { return {"standard", std::move(slots)}; }
LensSpelling cvFisheye(std::vector<int> slots) { return {"fisheye", std::move(slots)}; }
LensSpelling nerf(const char* name, std::vector<int> slots) { return {name, std::move(slots)}; }
const LensSpelling kBlenderPerspective{"PERSP", {}};
const LensSpelling kBlenderEquidistant{"FISHEYE_EQUIDISTANT", {}};
const LensSpelling kBlenderEquirectangular{"EQUIRECTANGULAR", {}};
constexpr int _ = -1;  // a slot no coefficient fills

std::deque<LensModelInfo>& modelTable() {
  // One row per model, in COLMAP's id order: id, COLMAP's name, id and parameters, fisheye,
  // the formula (terms or own), and the OpenCV, nerfstudio and Blender spellings.
  // clang-format off
  static std::deque<LensModelInfo> models = {
    {LensModelId::SimplePinhole, "SIMPLE_PINHOLE", 0, {"f", "cx", "cy"}, false,
     noTerms, nullptr, openCV({_, _, _, _}), nerf("SIMPLE_PINHOLE", {_, _, _, _, _, _}), kBlenderPerspective},
    {LensModelId::Pinhole, "PINHOLE", 1, {"fx", "fy", "cx", "cy"}, false,
     noTerms, nullptr, openCV({_, _, _, _}), nerf("PINHOLE", {_, _, _, _, _, _}), kBlenderPerspective},
    {LensModelId::SimpleRadial, "SIMPLE_RADIAL", 2, {"f", "cx", "cy", "k"}, false,
     oneRadialTerm, nullptr, openCV({0, _, _, _}), nerf("SIMPLE_RADIAL", {0, _, _, _, _, _}), kNone},
    {LensModelId::Radial, "RADIAL", 3, {"f", "cx", "cy", "k1", "k2"}, false,
     twoRadialTerms, nullptr, openCV({0, 1, _, _}), nerf("RADIAL", {0, 1, _, _, _, _}), kNone},
    {LensModelId::OpenCV, "OPENCV", 4, {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"}, false,
     openCVTerms, nullptr, openCV({0, 1, 2, 3}), nerf("OPENCV", {0, 1, _, _, 2, 3}), kNone},
    {LensModelId::OpenCVFisheye, "OPENCV_FISHEYE", 5, {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"}, true,
     openCVFisheyeTerms, nullptr, cvFisheye({0, 1, 2, 3}), nerf("OPENCV_FISHEYE", {0, 1, 2, 3}), kNone},
    // nerfstudio's k3 is FULL_OPENCV's k3 (its k4 k5 k6, the denominator, have no slot).
    {LensModelId::FullOpenCV, "FULL_OPENCV", 6,
     {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"}, false,
     fullOpenCVTerms, nullptr, openCV({0, 1, 2, 3, 4, 5, 6, 7}), nerf("OPENCV", {0, 1, 4, _, 2, 3}), kNone},
    {LensModelId::FOV, "FOV", 7, {"fx", "fy", "cx", "cy", "omega"}, false,
     nullptr, &kFovFormula, kNone, kNone, kNone},
    {LensModelId::SimpleRadialFisheye, "SIMPLE_RADIAL_FISHEYE", 8, {"f", "cx", "cy", "k"}, true,
     oneRadialTerm, nullptr, cvFisheye({0, _, _, _}), nerf("OPENCV_FISHEYE", {0, _, _, _}), kNone},
    {LensModelId::RadialFisheye, "RADIAL_FISHEYE", 9, {"f", "cx", "cy", "k1", "k2"}, true,
     twoRadialTerms, nullptr, cvFisheye({0, 1, _, _}), nerf("OPENCV_FISHEYE", {0, 1, _, _}), kNone},
    {LensModelId::ThinPrismFisheye, "THIN_PRISM_FISHEYE", 10,
     {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "sx1", "sy1"}, true,
     thinPrismTerms, nullptr, kNone, kNone, kNone},
    // Project Aria's Fisheye624 (nerfstudio's FISHEYE624 is not read: its file keys differ).
    {LensModelId::RadTanThinPrismFisheye, "RAD_TAN_THIN_PRISM_FISHEYE", 11,
     {"fx", "fy", "cx", "cy", "k0", "k1", "k2", "k3", "k4", "k5", "p0", "p1", "s0", "s1", "s2", "s3"}, true,
     nullptr, &kRadTanThinPrismFormula, kNone, kNone, kNone},
    {LensModelId::SimpleDivision, "SIMPLE_DIVISION", 12, {"f", "cx", "cy", "k"}, false,
     nullptr, &kDivisionFormula, kNone, kNone, kNone},
    {LensModelId::Division, "DIVISION", 13, {"fx", "fy", "cx", "cy", "k"}, false,
     nullptr, &kDivisionFormula, kNone, kNone, kNone},
    // The equidistant fisheye: cv::fisheye and nerfstudio's OPENCV_FISHEYE with k = 0, and
    // Blender's (Cycles') equidistant fisheye panorama.
    {LensModelId::SimpleFisheye, "SIMPLE_FISHEYE", 14, {"f", "cx", "cy"}, true,
     noTerms, nullptr, cvFisheye({_, _, _, _}), nerf("OPENCV_FISHEYE", {_, _, _, _}), kBlenderEquidistant},
    {LensModelId::Fisheye, "FISHEYE", 15, {"fx", "fy", "cx", "cy"}, true,
     noTerms, nullptr, cvFisheye({_, _, _, _}), nerf("OPENCV_FISHEYE", {_, _, _, _}), kBlenderEquidistant},
    {LensModelId::EUCM, "EUCM", 16, {"fx", "fy", "cx", "cy", "alpha", "beta"}, false,
     nullptr, &kEucmFormula, kNone, kNone, kNone},
    {LensModelId::Equirectangular, "EQUIRECTANGULAR", 17, {"w", "h"}, false,
     nullptr, &kEquirectangularFormula, kNone, kNone, kBlenderEquirectangular},
  };
  // clang-format on
  return models;
}

}  // namespace

const std::deque<LensModelInfo>& lensModels() { return modelTable(); }

const LensModelInfo& registerLensModel(LensModelInfo row) {
  if ((row.terms == nullptr) == (row.formula == nullptr) ||
      (row.formula && row.formula->profile == nullptr))
    throw Error(cat("lens model ", row.name,
                    ": needs exactly one formula (terms of the polynomial form, or a profile)"));
  if (row.paramNames.size() < 3)
    throw Error(cat("lens model ", row.name, ": needs at least f, cx, cy"));
  for (const LensModelInfo& m : lensModels())
    if (m.id == row.id || m.colmapId == row.colmapId || std::string(m.name) == row.name)
      throw Error(cat("lens model ", row.name, " (id ", int(row.id), ", COLMAP id ", row.colmapId,
                      "): its id, COLMAP id or name is taken by ", m.name));
  modelTable().push_back(std::move(row));
  return modelTable().back();
}

void unregisterLensModel(LensModelId id) {
  std::deque<LensModelInfo>& models = modelTable();
  if (models.empty() || models.back().id != id)
    throw Error(cat("lens model id ", int(id), " is not the last one registered"));
  models.pop_back();
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
  if (m.ownMap()) {
    m.formula->intrinsicsOf(params_.data(), c.fx, c.fy, c.cx, c.cy);
  } else {
    c.fx = params_[0], c.fy = params_[single ? 0 : 1];
    c.cx = params_[single ? 1 : 2], c.cy = params_[single ? 2 : 3];
  }
  c.fisheye = m.fisheye || (m.formula && m.formula->overTheta);
  const std::vector<double> k = distortion();
  if (m.formula && m.formula->check) m.formula->check(m.name, k.data());
  if (c.fx <= 0 || c.fy <= 0)
    throw Error(
        cat("camera model ", m.name, ": focal length must be > 0 (got ", c.fx, ", ", c.fy, ")"));
  if (m.formula) {
    c.formula = m.formula;
    c.coefficients = k;
  } else {
    c.terms = m.terms(k.data());
    c.terms.rational = c.terms.den[1] != 0 || c.terms.den[2] != 0 || c.terms.den[3] != 0;
    c.terms.radialOnly = c.terms.p1 == 0 && c.terms.p2 == 0 && c.terms.sx1 == 0 && c.terms.sy1 == 0;
    c.terms.identity = c.terms.radialOnly && !c.terms.rational && c.terms.num[1] == 0 &&
                       c.terms.num[2] == 0 && c.terms.num[3] == 0 && c.terms.num[4] == 0;
  }
  valid_ = findValidRegion();
  c.bounded = valid_.bounded();
  c.maxUndistorted = valid_.maxUndistorted;
  c.maxDistorted = valid_.maxDistorted;
  c.nonRadialLimit =
      c.bounded ? valid_.maxDistorted + nonRadialReach() : std::numeric_limits<double>::infinity();
  if (c.formula && c.formula->reach && c.bounded)
    c.nonRadialLimit = valid_.maxDistorted + c.formula->reach(k.data(), valid_.maxDistorted);
  tabulateInverse();
}

double Lens::fx() const { return inverse_.fx; }
double Lens::fy() const { return inverse_.fy; }
double Lens::cx() const { return inverse_.cx; }
double Lens::cy() const { return inverse_.cy; }

std::vector<double> Lens::distortion() const {
  return {params_.begin() + long(info().intrinsicCount()), params_.end()};
}

bool Lens::distorted() const {
  if (inverse_.fisheye) return true;
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

glm::dvec2 Lens::distort(const glm::dvec2& p, glm::dmat2* jacobian) const {
  if (info().ownMap()) {  // no distortion about a principal point: the identity
    if (jacobian) *jacobian = glm::dmat2(1.0);
    return p;
  }
  if (inverse_.formula) {
    glm::dvec2 d;
    double j[4] = {};
    distortByFormula(inverse_, p.x, p.y, d.x, d.y, jacobian ? j : nullptr);
    if (jacobian) *jacobian = glm::dmat2(j[0], j[1], j[2], j[3]);  // column by column
    return d;
  }
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
  const bool fisheye = inverse_.fisheye;
  LensValidRegion region;
  region.maxUndistorted = region.maxDistorted = fisheye ? kPi : kInf;
  if (info().ownMap()) {  // every pixel has its ray
    region.maxUndistorted = region.maxDistorted = kInf;
    return region;
  }
  if (!inverse_.formula && inverse_.terms.identity) return region;

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
  if (inverse_.formula || inverse_.terms.identity) return;        // a formula's inverse needs none
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
  if (info().ownMap()) return distorted;
  glm::dvec2 u;
  if (!undistortOne(inverse_, distorted.x, distorted.y, u.x, u.y)) return std::nullopt;
  return u;
}

std::optional<glm::dvec2> Lens::project(const glm::dvec3& dir) const {
  if (!std::isfinite(dir.x) || !std::isfinite(dir.y) || !std::isfinite(dir.z)) return std::nullopt;
  if (info().ownMap()) {
    const double d[3] = {dir.x, dir.y, dir.z};
    glm::dvec2 pixel;
    if (!inverse_.formula->pixelOf(params_.data(), d, pixel.x, pixel.y)) return std::nullopt;
    return pixel;
  }
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
  const glm::dvec2 d = distort(undistorted, radialOnly() ? nullptr : &jacobian);
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
