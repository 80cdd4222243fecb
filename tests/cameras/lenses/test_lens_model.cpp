// COLMAP's lens models (issue 11): the model table against COLMAP's, the forward map against an
// independent reference written in this file straight from the formulas of COLMAP's
// src/colmap/sensor/models.h (and shown to catch wrong conventions), the analytic Jacobian
// against finite differences, the inverse by Newton's method (round trips in normalised
// coordinates and in pixels), the valid region against closed forms and at its boundary, and
// extremes (k = ±0.5, a 190° fisheye, principal points outside the image, focal lengths from
// 10 px to 1e6 px). COLMAP's own test (src/colmap/sensor/models_test.cc) supplies parameter
// sets and the points it checks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "cameras/lenses/lens_model.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "tests/camera_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

constexpr double kDeg = kPi / 180;
using M = LensModelId;
using test::angleBetween;
using test::errorOf;

struct LensCase {
  const char* label;
  M model;
  std::vector<double> params;
};

// COLMAP's parameter sets from models_test.cc (taken as facts).
std::vector<LensCase> colmapCases() {
  return {
      {"SIMPLE_PINHOLE", M::SimplePinhole, {655.123, 386.123, 511.123}},
      {"PINHOLE", M::Pinhole, {651.123, 655.123, 386.123, 511.123}},
      {"SIMPLE_RADIAL k=0", M::SimpleRadial, {651.123, 386.123, 511.123, 0}},
      {"SIMPLE_RADIAL k=0.1", M::SimpleRadial, {651.123, 386.123, 511.123, 0.1}},
      {"RADIAL 0 0", M::Radial, {651.123, 386.123, 511.123, 0, 0}},
      {"RADIAL 0.1 0", M::Radial, {651.123, 386.123, 511.123, 0.1, 0}},
      {"RADIAL 0 0.05", M::Radial, {651.123, 386.123, 511.12, 0, 0.05}},
      {"RADIAL 0.05 0.03", M::Radial, {651.123, 386.123, 511.123, 0.05, 0.03}},
      {"OPENCV", M::OpenCV, {651.123, 655.123, 386.123, 511.123, -0.471, 0.223, -0.001, 0.001}},
      {"OPENCV_FISHEYE",
       M::OpenCVFisheye,
       {651.123, 655.123, 386.123, 511.123, -0.471, 0.223, -0.001, 0.001}},
      {"FULL_OPENCV",
       M::FullOpenCV,
       {651.123, 655.123, 386.123, 511.123, -0.471, 0.223, -0.001, 0.001, 0.001, 0.02, -0.02,
        0.001}},
      {"SIMPLE_RADIAL_FISHEYE k=0", M::SimpleRadialFisheye, {651.123, 386.123, 511.123, 0}},
      {"SIMPLE_RADIAL_FISHEYE k=0.1", M::SimpleRadialFisheye, {651.123, 386.123, 511.123, 0.1}},
      {"RADIAL_FISHEYE 0 0", M::RadialFisheye, {651.123, 386.123, 511.123, 0, 0}},
      {"RADIAL_FISHEYE 0 0.1", M::RadialFisheye, {651.123, 386.123, 511.123, 0, 0.1}},
      {"RADIAL_FISHEYE 0 0.05", M::RadialFisheye, {651.123, 386.123, 511.123, 0, 0.05}},
      {"RADIAL_FISHEYE 0 0.03", M::RadialFisheye, {651.123, 386.123, 511.123, 0, 0.03}},
      {"THIN_PRISM_FISHEYE",
       M::ThinPrismFisheye,
       {651.123, 655.123, 386.123, 511.123, -0.471, 0.223, -0.001, 0.001, 0.001, 0.02, -0.02,
        0.001}},
  };
}

// Our own harder sets: strong radial distortion both ways, folds (polynomial, rational,
// fisheye), strong tangential and thin-prism terms.
std::vector<LensCase> extremeCases() {
  return {
      {"SIMPLE_RADIAL k=+0.5", M::SimpleRadial, {500, 320, 240, 0.5}},
      {"SIMPLE_RADIAL k=-0.5", M::SimpleRadial, {500, 320, 240, -0.5}},
      {"RADIAL fold", M::Radial, {500, 320, 240, 0.1, -0.05}},
      {"OPENCV k1=+0.5", M::OpenCV, {500, 510, 320, 240, 0.5, 0, 0.01, -0.01}},
      {"OPENCV k1=-0.5", M::OpenCV, {500, 510, 320, 240, -0.5, 0, 0.01, -0.01}},
      {"OPENCV tangential", M::OpenCV, {500, 510, 320, 240, -0.2, 0.05, 0.03, -0.02}},
      {"FULL_OPENCV rational fold", M::FullOpenCV, {500, 510, 320, 240, 0, 0, 0, 0, 0, 1, 0, 0}},
      {"FULL_OPENCV pole",
       M::FullOpenCV,
       {500, 510, 320, 240, 0.1, 0, 0.002, 0.001, 0, -0.2, 0, 0}},
      {"OPENCV_FISHEYE equidistant", M::OpenCVFisheye, {300, 300, 320, 240, 0, 0, 0, 0}},
      {"SIMPLE_RADIAL_FISHEYE fold", M::SimpleRadialFisheye, {300, 320, 240, -0.1}},
      {"RADIAL_FISHEYE -0.05 0.002", M::RadialFisheye, {300, 320, 240, -0.05, 0.002}},
      {"THIN_PRISM_FISHEYE prism",
       M::ThinPrismFisheye,
       {300, 310, 320, 240, 0.02, -0.01, 0.004, -0.003, 0.001, 0, 0.01, -0.008}},
  };
}

// The models COLMAP 4 added (issue 40), each reaching past what it sees inside a 1600 x 1200
// image (behind the camera, a fold, the limit of its formula).
std::vector<LensCase> colmap4Cases() {
  return {
      {"FOV ω=0.9", M::FOV, {500, 510, 320, 240, 0.9}},
      {"FOV ω=0", M::FOV, {500, 510, 320, 240, 0}},
      {"SIMPLE_DIVISION k=-0.3 (behind the camera)", M::SimpleDivision, {300, 320, 240, -0.3}},
      {"DIVISION k=+0.2 (fold)", M::Division, {500, 510, 320, 240, 0.2}},
      {"SIMPLE_FISHEYE", M::SimpleFisheye, {300, 320, 240}},
      {"FISHEYE", M::Fisheye, {300, 310, 320, 240}},
      {"EUCM α=0.6 β=1.1 (fold)", M::EUCM, {400, 410, 320, 240, 0.6, 1.1}},
      {"EUCM α=0.3 β=0.8", M::EUCM, {400, 410, 320, 240, 0.3, 0.8}},
      {"EQUIRECTANGULAR", M::Equirectangular, {1600, 800}},
      {"RAD_TAN_THIN_PRISM_FISHEYE",
       M::RadTanThinPrismFisheye,
       {300, 310, 320, 240, 0.02, -0.01, 0.002, -1e-4, 0, 0, 0.004, -0.003, 0.01, -0.002, -0.008,
        0.001}},
  };
}

std::vector<LensCase> allCases() {
  std::vector<LensCase> all = colmapCases();
  for (LensCase& c : extremeCases()) all.push_back(std::move(c));
  for (LensCase& c : colmap4Cases()) all.push_back(std::move(c));
  return all;
}

bool isFisheyeModel(M m) {
  return m == M::OpenCVFisheye || m == M::SimpleRadialFisheye || m == M::RadialFisheye ||
         m == M::ThinPrismFisheye || m == M::SimpleFisheye || m == M::Fisheye ||
         m == M::RadTanThinPrismFisheye;
}

bool hasOneFocalLength(M m) {
  return m == M::SimplePinhole || m == M::SimpleRadial || m == M::Radial ||
         m == M::SimpleRadialFisheye || m == M::RadialFisheye || m == M::SimpleDivision ||
         m == M::SimpleFisheye;
}

// --- The independent reference: COLMAP's ImgFromCam, one model at a time ----------------------

/// The conventions the reference can get deliberately wrong, to show the checks catch them.
enum class Convention {
  Correct,
  TangentialSignFlipped,  ///< −p1, −p2
  TangentialSwapped,      ///< p1 and p2 exchanged
  DistortionOnPixels,     ///< the polynomial applied to f·(x/z) instead of x/z
  FisheyeOnTangent,       ///< a fisheye's polynomial applied to x/z instead of θ
};

std::optional<glm::dvec2> referencePixel(const LensCase& c, const glm::dvec3& X,
                                         Convention convention = Convention::Correct) {
  const std::vector<double>& p = c.params;
  if (c.model == M::Equirectangular) {  // EquirectangularCameraModel::ImgFromCam
    const double theta = std::atan2(X.x, X.z), phi = std::atan2(-X.y, std::hypot(X.x, X.z));
    return glm::dvec2((theta / (2 * kPi) + 0.5) * p[0], (0.5 - phi / kPi) * p[1]);
  }
  const bool one = hasOneFocalLength(c.model);
  const double f1 = p[0], f2 = p[one ? 0 : 1], c1 = p[one ? 1 : 2], c2 = p[one ? 2 : 3];
  const double* extra = p.data() + (one ? 3 : 4);
  // The division models and EUCM project (x, y, z) as a whole (no cheirality test for the
  // division models): the quadratic's root nearer the axis, ρ = 2 / (z + √(z² − 4kρ_xy²))
  // times (x, y); EUCM's (x, y) / (α √(β(x² + y²) + z²) + (1 − α) z).
  if (c.model == M::SimpleDivision || c.model == M::Division) {
    const double rxy = std::hypot(X.x, X.y), disc = X.z * X.z - 4 * rxy * rxy * extra[0];
    if (disc < 0) return std::nullopt;
    const double r = 2 / (X.z + std::sqrt(disc));
    return glm::dvec2(f1 * r * X.x + c1, f2 * r * X.y + c2);
  }
  if (c.model == M::EUCM) {
    const double alpha = extra[0], beta = extra[1];
    const double den =
        alpha * std::sqrt(beta * (X.x * X.x + X.y * X.y) + X.z * X.z) + (1 - alpha) * X.z;
    if (!(den > 0)) return std::nullopt;
    return glm::dvec2(f1 * X.x / den + c1, f2 * X.y / den + c2);
  }
  // (u, v): the point the distortion acts on. Pinhole models: (x/z, y/z). Fisheye models:
  // θ·(x, y)/|(x, y)| with θ the angle off-axis (COLMAP: atan(r); atan2 past 90°).
  double u = 0, v = 0;
  const bool fisheye = isFisheyeModel(c.model);
  if (fisheye && convention != Convention::FisheyeOnTangent) {
    const double r = std::hypot(X.x, X.y);
    const double theta = std::atan2(r, X.z);
    if (r > 0) u = theta * X.x / r, v = theta * X.y / r;
  } else {
    if (X.z <= 0) return std::nullopt;
    u = X.x / X.z, v = X.y / X.z;
  }
  double fx = f1, fy = f2, cx = c1, cy = c2;
  const std::vector<double> k(extra, p.data() + p.size());
  if (convention == Convention::DistortionOnPixels) u *= fx, v *= fy, fx = fy = 1;
  double p1 = 0, p2 = 0;
  const auto tangential = [&](double& du, double& dv) {
    if (convention == Convention::TangentialSignFlipped) p1 = -p1, p2 = -p2;
    if (convention == Convention::TangentialSwapped) std::swap(p1, p2);
    const double r2 = u * u + v * v;
    du += 2 * p1 * u * v + p2 * (r2 + 2 * u * u);
    dv += 2 * p2 * u * v + p1 * (r2 + 2 * v * v);
  };
  double du = 0, dv = 0;  // COLMAP's Distortion(): the offset added to (u, v)
  const double r2 = u * u + v * v;
  switch (c.model) {
    case M::SimplePinhole:
    case M::Pinhole:
    case M::SimpleFisheye:
    case M::Fisheye:
      break;
    case M::FOV: {  // FOVCameraModel::Distortion, its general branch (ω² and r² >= 1e-4)
      const double r = std::sqrt(r2), omega = k[0];
      if (omega != 0 && r > 0) {
        const double factor = std::atan(r * 2 * std::tan(omega / 2)) / (r * omega);
        du = u * factor - u, dv = v * factor - v;
      }
      break;
    }
    case M::SimpleRadial:
    case M::SimpleRadialFisheye:
      du = u * k[0] * r2, dv = v * k[0] * r2;
      break;
    case M::Radial:
    case M::RadialFisheye: {
      const double radial = k[0] * r2 + k[1] * r2 * r2;
      du = u * radial, dv = v * radial;
      break;
    }
    case M::OpenCV: {
      const double radial = k[0] * r2 + k[1] * r2 * r2;
      du = u * radial, dv = v * radial;
      p1 = k[2], p2 = k[3];
      tangential(du, dv);
      break;
    }
    case M::OpenCVFisheye: {
      const double radial =
          k[0] * r2 + k[1] * std::pow(r2, 2) + k[2] * std::pow(r2, 3) + k[3] * std::pow(r2, 4);
      du = u * radial, dv = v * radial;
      break;
    }
    case M::FullOpenCV: {
      const double radial = (1 + k[0] * r2 + k[1] * std::pow(r2, 2) + k[4] * std::pow(r2, 3)) /
                            (1 + k[5] * r2 + k[6] * std::pow(r2, 2) + k[7] * std::pow(r2, 3));
      du = u * radial - u, dv = v * radial - v;
      p1 = k[2], p2 = k[3];
      tangential(du, dv);
      break;
    }
    case M::ThinPrismFisheye: {
      const double radial =
          k[0] * r2 + k[1] * std::pow(r2, 2) + k[4] * std::pow(r2, 3) + k[5] * std::pow(r2, 4);
      du = u * radial + k[6] * r2, dv = v * radial + k[7] * r2;
      p1 = k[2], p2 = k[3];
      tangential(du, dv);
      break;
    }
    case M::RadTanThinPrismFisheye: {  // RadTanThinPrismFisheyeModel::Distortion
      double th = 1, power = 1;
      for (int i = 0; i < 6; ++i) power *= r2, th += k[size_t(i)] * power;
      const double x = th * u, y = th * v, q2 = x * x + y * y;
      double p0 = k[6], p1r = k[7];
      if (convention == Convention::TangentialSignFlipped) p0 = -p0, p1r = -p1r;
      if (convention == Convention::TangentialSwapped) std::swap(p0, p1r);
      du = x + 2 * p1r * x * y + p0 * (q2 + 2 * x * x) + k[8] * q2 + k[9] * q2 * q2 - u;
      dv = y + 2 * p0 * x * y + p1r * (q2 + 2 * y * y) + k[10] * q2 + k[11] * q2 * q2 - v;
      break;
    }
    default:  // the division models, EUCM and EQUIRECTANGULAR: above
      return std::nullopt;
  }
  return glm::dvec2(fx * (u + du) + cx, fy * (v + dv) + cy);
}

// --- Sampling ----------------------------------------------------------------------------------

Lens lensOf(const LensCase& c) { return Lens(c.model, c.params); }

/// How far out the random points go: 98% of the valid region (r or θ), and r <= 3 (71.6°
/// off-axis) for the pinhole models without a fold.
double sampleRadius(const Lens& lens) {
  const double cap = lens.overTheta() ? kPi : 3.0;
  return 0.98 * std::min(lens.validRegion().maxUndistorted, cap);
}

glm::dvec2 randomInDisc(std::mt19937_64& rng, double radius) {
  std::uniform_real_distribution<double> unit(0, 1);
  const double r = radius * std::sqrt(unit(rng)), phi = 2 * kPi * unit(rng);
  return {r * std::cos(phi), r * std::sin(phi)};
}

/// The camera-space direction of undistorted normalised coordinates.
glm::dvec3 directionOf(const Lens& lens, const glm::dvec2& u) {
  if (!lens.overTheta()) return glm::normalize(glm::dvec3(u, 1.0));
  const double theta = glm::length(u);
  if (theta == 0) return {0, 0, 1};
  return {std::sin(theta) * u.x / theta, std::sin(theta) * u.y / theta, std::cos(theta)};
}

/// Whether the distortion has a term that is not radial (it can fold the map in 2D).
bool hasNonRadialTerms(const LensCase& c) {
  const std::vector<double>& p = c.params;
  switch (c.model) {
    case M::OpenCV:
      return p[6] != 0 || p[7] != 0;
    case M::FullOpenCV:
      return p[6] != 0 || p[7] != 0;
    case M::ThinPrismFisheye:
      return p[6] != 0 || p[7] != 0 || p[10] != 0 || p[11] != 0;
    case M::RadTanThinPrismFisheye:
      return true;
    default:
      return false;
  }
}

/// Largest pixel distance between the library's projection and the reference's over random
/// directions in the valid region (directions the library refuses are skipped, and counted).
double maxReferenceDiscrepancy(const LensCase& c, Convention convention, int* compared = nullptr) {
  const Lens lens = lensOf(c);
  std::mt19937_64 rng(7);
  double worst = 0;
  int n = 0;
  for (int i = 0; i < 2000; ++i) {
    const glm::dvec3 dir = directionOf(lens, randomInDisc(rng, sampleRadius(lens)));
    const std::optional<glm::dvec2> got = lens.project(dir * 3.0);  // any length
    const std::optional<glm::dvec2> want = referencePixel(c, dir, convention);
    if (!got || !want) continue;
    worst = std::max(worst, glm::length(*got - *want));
    ++n;
  }
  if (compared) *compared = n;
  return worst;
}

// --- The model table ---------------------------------------------------------------------------

TEST(LensModelTable, MatchesColmapIdsNamesAndParameters) {
  // COLMAP's models.h: the CameraModelId enum, model_name and InitializeParamsInfo() of each
  // model, and FISHEYE_CAMERA_MODEL_CASES.
  struct Fact {
    const char* name;
    int id;
    const char* params;
    bool fisheye;
  };
  const std::vector<Fact> facts = {
      {"SIMPLE_PINHOLE", 0, "f, cx, cy", false},
      {"PINHOLE", 1, "fx, fy, cx, cy", false},
      {"SIMPLE_RADIAL", 2, "f, cx, cy, k", false},
      {"RADIAL", 3, "f, cx, cy, k1, k2", false},
      {"OPENCV", 4, "fx, fy, cx, cy, k1, k2, p1, p2", false},
      {"OPENCV_FISHEYE", 5, "fx, fy, cx, cy, k1, k2, k3, k4", true},
      {"FULL_OPENCV", 6, "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6", false},
      {"FOV", 7, "fx, fy, cx, cy, omega", false},
      {"SIMPLE_RADIAL_FISHEYE", 8, "f, cx, cy, k", true},
      {"RADIAL_FISHEYE", 9, "f, cx, cy, k1, k2", true},
      {"THIN_PRISM_FISHEYE", 10, "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1", true},
      {"RAD_TAN_THIN_PRISM_FISHEYE", 11,
       "fx, fy, cx, cy, k0, k1, k2, k3, k4, k5, p0, p1, s0, s1, s2, s3", true},
      {"SIMPLE_DIVISION", 12, "f, cx, cy, k", false},
      {"DIVISION", 13, "fx, fy, cx, cy, k", false},
      {"SIMPLE_FISHEYE", 14, "f, cx, cy", true},
      {"FISHEYE", 15, "fx, fy, cx, cy", true},
      {"EUCM", 16, "fx, fy, cx, cy, alpha, beta", false},
      {"EQUIRECTANGULAR", 17, "w, h", false},
  };
  ASSERT_EQ(lensModels().size(), facts.size());
  for (size_t i = 0; i < facts.size(); ++i) {
    const LensModelInfo& m = lensModels()[i];
    SCOPED_TRACE(facts[i].name);
    EXPECT_STREQ(m.name, facts[i].name);
    EXPECT_EQ(m.colmapId, facts[i].id);
    EXPECT_EQ(join(m.paramNames, ", "), facts[i].params);
    EXPECT_EQ(m.fisheye, facts[i].fisheye);
    EXPECT_EQ(&findLensModel(facts[i].name), &m);
    EXPECT_EQ(findLensModelByColmapId(facts[i].id), &m);
    EXPECT_EQ(&lensModelInfo(m.id), &m);
  }
  EXPECT_EQ(findLensModelByColmapId(18), nullptr);
  EXPECT_EQ(findLensModelByColmapId(-1), nullptr);
}

TEST(LensModelNames, UnknownNamesAreRefusedWithTheName) {
  EXPECT_EQ(findLensModel("opencv_fisheye").id, M::OpenCVFisheye);  // case-insensitive
  try {
    findLensModel("SIMPLE_RADAIL");
    ADD_FAILURE() << "a misspelt model was accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'SIMPLE_RADAIL'"), std::string::npos) << what;
    EXPECT_NE(what.find("did you mean 'SIMPLE_RADIAL'"), std::string::npos) << what;
  }
  try {
    findLensModel("KANNALA_BRANDT");  // a name COLMAP does not have
    ADD_FAILURE() << "an unsupported model was accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'KANNALA_BRANDT'"), std::string::npos) << what;
    EXPECT_NE(what.find("THIN_PRISM_FISHEYE"), std::string::npos) << what;  // the list
  }
}

TEST(LensModelNames, BadParametersAreRefused) {
  try {
    Lens(M::SimpleRadial, {500, 320, 240});
    ADD_FAILURE() << "a wrong parameter count was accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("SIMPLE_RADIAL takes 4 parameters (f cx cy k), got 3"), std::string::npos)
        << what;
  }
  EXPECT_THROW(Lens(M::Pinhole, {500, 0, 320, 240}), Error);
  EXPECT_THROW(Lens(M::SimplePinhole, {-1, 320, 240}), Error);
  EXPECT_THROW(Lens(M::OpenCV, {500, 500, 320, 240, std::nan(""), 0, 0, 0}), Error);
}

// --- The forward map against the independent reference ----------------------------------------

TEST(LensModelReference, ProjectMatchesColmapsFormulas) {
  for (const LensCase& c : allCases()) {
    SCOPED_TRACE(c.label);
    int compared = 0;
    EXPECT_LT(maxReferenceDiscrepancy(c, Convention::Correct, &compared), 1e-8);
    EXPECT_GT(compared, hasNonRadialTerms(c) ? 1500 : 1999);
  }
}

// The same comparison, against a reference with one convention wrong, fails: the check above
// has the power to catch each of these mistakes.
TEST(LensModelReference, WrongConventionsAreCaught) {
  const LensCase tangential{
      "OPENCV", M::OpenCV, {651.123, 655.123, 386.123, 511.123, -0.2, 0.05, 0.004, -0.003}};
  EXPECT_LT(maxReferenceDiscrepancy(tangential, Convention::Correct), 1e-8);
  EXPECT_GT(maxReferenceDiscrepancy(tangential, Convention::TangentialSignFlipped), 1.0);
  EXPECT_GT(maxReferenceDiscrepancy(tangential, Convention::TangentialSwapped), 1.0);
  EXPECT_GT(maxReferenceDiscrepancy(tangential, Convention::DistortionOnPixels), 1.0);
  // COLMAP's own OPENCV set: its tangential terms are small, still far above the tolerance.
  const LensCase colmapOpenCV = colmapCases()[8];
  ASSERT_STREQ(colmapOpenCV.label, "OPENCV");
  EXPECT_GT(maxReferenceDiscrepancy(colmapOpenCV, Convention::TangentialSignFlipped), 0.01);
  const LensCase radial{"SIMPLE_RADIAL", M::SimpleRadial, {651.123, 386.123, 511.123, 0.1}};
  EXPECT_GT(maxReferenceDiscrepancy(radial, Convention::DistortionOnPixels), 1.0);
  const LensCase fisheye = colmapCases()[9];
  ASSERT_STREQ(fisheye.label, "OPENCV_FISHEYE");
  EXPECT_LT(maxReferenceDiscrepancy(fisheye, Convention::Correct), 1e-8);
  EXPECT_GT(maxReferenceDiscrepancy(fisheye, Convention::FisheyeOnTangent), 1.0);
  const LensCase prism = extremeCases().back();
  ASSERT_STREQ(prism.label, "THIN_PRISM_FISHEYE prism");
  EXPECT_GT(maxReferenceDiscrepancy(prism, Convention::TangentialSwapped), 1.0);
}

// --- Closed forms, one per family at least -----------------------------------------------------

TEST(LensModelClosedForm, KnownPoints) {
  // SIMPLE_RADIAL: x = f·u·(1 + k r²) + cx. (0.3, −0.4): r² = 0.25, 1 + 0.1·0.25 = 1.025.
  const Lens simpleRadial(M::SimpleRadial, {100, 50, 40, 0.1});
  std::optional<glm::dvec2> px = simpleRadial.project({0.3, -0.4, 1});
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x, 100 * 0.3 * 1.025 + 50, 1e-12);   // 80.75
  EXPECT_NEAR(px->y, 100 * -0.4 * 1.025 + 40, 1e-12);  // −1
  // RADIAL: (0.6, 0.8): r² = 1, 1 + 0.1 + 0.01 = 1.11; any length of the direction.
  px = Lens(M::Radial, {100, 0, 0, 0.1, 0.01}).project({1.2, 1.6, 2});
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x, 66.6, 1e-12);
  EXPECT_NEAR(px->y, 88.8, 1e-12);
  // OPENCV tangential alone: (0.2, 0.1), p1 = 0.01, p2 = 0.02:
  // u' = 0.2 + 2·0.01·0.02 + 0.02·(0.05 + 0.08) = 0.203, v' = 0.1 + 2·0.02·0.02 + 0.01·(0.05 +
  // 0.02) = 0.1015.
  const glm::dvec2 d =
      Lens(M::OpenCV, {1, 1, 0, 0, 0, 0, 0.01, 0.02}).distort(glm::dvec2(0.2, 0.1));
  EXPECT_NEAR(d.x, 0.203, 1e-15);
  EXPECT_NEAR(d.y, 0.1015, 1e-15);
  // FULL_OPENCV with k4 = 1 alone: u' = u / (1 + r²); u = 0.5 -> 0.4.
  px = Lens(M::FullOpenCV, {200, 200, 10, 20, 0, 0, 0, 0, 0, 1, 0, 0}).project({1, 0, 2});
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x, 200 * 0.4 + 10, 1e-12);
  EXPECT_NEAR(px->y, 20, 1e-12);
  // Equidistant fisheye (OPENCV_FISHEYE, zero coefficients): the pixel is θ·f from the centre
  // along the azimuth. 60° off-axis at azimuth 30°.
  const Lens equidistant(M::OpenCVFisheye, {300, 300, 320, 240, 0, 0, 0, 0});
  const glm::dvec3 dir(std::sin(60 * kDeg) * std::cos(30 * kDeg),
                       std::sin(60 * kDeg) * std::sin(30 * kDeg), std::cos(60 * kDeg));
  px = equidistant.project(dir);
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x, 320 + 300 * (kPi / 3) * std::cos(30 * kDeg), 1e-10);
  EXPECT_NEAR(px->y, 240 + 300 * (kPi / 3) * std::sin(30 * kDeg), 1e-10);
  const std::optional<glm::dvec3> back = equidistant.unproject(*px);
  ASSERT_TRUE(back);
  EXPECT_LT(angleBetween(*back, dir), 1e-14);
  // SIMPLE_RADIAL_FISHEYE, k = 0.1: θ = 1 rad -> θ_d = 1.1.
  px = Lens(M::SimpleRadialFisheye, {100, 0, 0, 0.1}).project({std::sin(1.0), 0, std::cos(1.0)});
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x, 110, 1e-12);
  EXPECT_NEAR(px->y, 0, 1e-12);
  // THIN_PRISM_FISHEYE with sx1 = 0.01 alone: u' = θ + 0.01·θ², v' = 0 along +x.
  px = Lens(M::ThinPrismFisheye, {100, 100, 0, 0, 0, 0, 0, 0, 0, 0, 0.01, 0})
           .project({std::sin(1.0), 0, std::cos(1.0)});
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x, 101, 1e-12);
  EXPECT_NEAR(px->y, 0, 1e-12);
}

TEST(LensModelClosedForm, UndistortIsTheIdentityForThePinholes) {
  for (const Lens& lens :
       {Lens(M::SimplePinhole, {500, 320, 240}), Lens(M::Pinhole, {500, 400, 320, 240}),
        Lens(M::SimpleRadial, {500, 320, 240, 0})}) {
    for (const glm::dvec2 d :
         {glm::dvec2(0), glm::dvec2(0.1, -0.7), glm::dvec2(1e6, -3e5), glm::dvec2(1e-300, 2.5)}) {
      const std::optional<glm::dvec2> u = lens.undistort(d);
      ASSERT_TRUE(u);
      EXPECT_EQ(u->x, d.x);  // exact: no Newton
      EXPECT_EQ(u->y, d.y);
      glm::dmat2 jacobian;
      EXPECT_EQ(lens.distort(d, &jacobian), d);
      EXPECT_EQ(jacobian, glm::dmat2(1.0));
    }
    EXPECT_FALSE(lens.validRegion().bounded());
    EXPECT_EQ(lens.validRegion().text(false), "unbounded");
    EXPECT_FALSE(lens.project({1, 0, 0}));  // z = 0: no image
    EXPECT_FALSE(lens.project({0, 0, -1}));
  }
}

// --- The Jacobian ------------------------------------------------------------------------------

TEST(LensModelJacobian, MatchesCentralDifferences) {
  for (const LensCase& c : allCases()) {
    SCOPED_TRACE(c.label);
    const Lens lens = lensOf(c);
    std::mt19937_64 rng(11);
    for (int i = 0; i < 200; ++i) {
      const glm::dvec2 u = randomInDisc(rng, sampleRadius(lens));
      glm::dmat2 jacobian;
      lens.distort(u, &jacobian);
      const double h = 1e-6;
      for (int axis = 0; axis < 2; ++axis) {
        glm::dvec2 e(0.0);
        e[axis] = h;
        const glm::dvec2 fd = (lens.distort(u + e) - lens.distort(u - e)) / (2 * h);
        const double scale = std::max(1.0, glm::length(jacobian[axis]));
        EXPECT_NEAR(jacobian[axis].x, fd.x, 1e-6 * scale)
            << "d/d"
            << "uv"[axis] << " at " << u.x << ", " << u.y;
        EXPECT_NEAR(jacobian[axis].y, fd.y, 1e-6 * scale)
            << "d/d"
            << "uv"[axis] << " at " << u.x << ", " << u.y;
      }
    }
  }
}

// --- Round trips -------------------------------------------------------------------------------

TEST(LensModelRoundTrip, DistortUndistortInNormalisedCoordinates) {
  for (const LensCase& c : allCases()) {
    SCOPED_TRACE(c.label);
    const Lens lens = lensOf(c);
    std::mt19937_64 rng(13);
    int checked = 0;
    for (int i = 0; i < 2000; ++i) {
      const glm::dvec2 u = randomInDisc(rng, sampleRadius(lens));
      glm::dmat2 jacobian;
      const glm::dvec2 d = lens.distort(u, &jacobian);
      if (hasNonRadialTerms(c) && !(glm::determinant(jacobian) > 0)) continue;  // 2D fold
      const std::optional<glm::dvec2> x = lens.undistort(d);
      ASSERT_TRUE(x) << "no inverse for " << u.x << ", " << u.y;
      EXPECT_LE(glm::length(*x - u), 1e-9) << u.x << ", " << u.y;  // inverse ∘ forward
      EXPECT_LE(glm::length(lens.distort(*x) - d), 1e-12 * std::max(1.0, glm::length(d)));
      ++checked;
    }
    EXPECT_GT(checked, 1500);
    // Forward ∘ inverse from the distorted side: random points inside the distorted radius of
    // the fold (the radial models must invert every one of them).
    const double maxD = std::min(lens.validRegion().maxDistorted, 50.0);
    for (int i = 0; i < 2000; ++i) {
      const glm::dvec2 d = randomInDisc(rng, 0.999 * maxD);
      const std::optional<glm::dvec2> x = lens.undistort(d);
      if (!hasNonRadialTerms(c)) {
        ASSERT_TRUE(x) << "no inverse for " << d.x << ", " << d.y;
      }
      if (!x) continue;
      EXPECT_LE(glm::length(lens.distort(*x) - d), 1e-9 * std::max(1.0, glm::length(d)));
      EXPECT_LT(glm::length(*x), lens.validRegion().maxUndistorted);
    }
  }
}

TEST(LensModelRoundTrip, ProjectUnprojectInPixels) {
  for (const LensCase& c : allCases()) {
    SCOPED_TRACE(c.label);
    const Lens lens = lensOf(c);
    std::mt19937_64 rng(17);
    // Directions -> pixels -> directions.
    for (int i = 0; i < 1000; ++i) {
      const glm::dvec3 dir = directionOf(lens, randomInDisc(rng, sampleRadius(lens)));
      const std::optional<glm::dvec2> px = lens.project(dir);
      if (!px) continue;
      const std::optional<glm::dvec3> back = lens.unproject(*px);
      ASSERT_TRUE(back);
      EXPECT_NEAR(glm::length(*back), 1.0, 1e-14);
      EXPECT_LT(angleBetween(*back, dir), 1e-9);
    }
    // Pixels of a 1600 x 1200 image around the principal point -> directions -> pixels.
    std::uniform_real_distribution<double> col(lens.cx() - 800, lens.cx() + 800);
    std::uniform_real_distribution<double> row(lens.cy() - 600, lens.cy() + 600);
    for (int i = 0; i < 2000; ++i) {
      const glm::dvec2 pixel(col(rng), row(rng));
      const std::optional<glm::dvec3> dir = lens.unproject(pixel);
      if (!dir) continue;
      const std::optional<glm::dvec2> again = lens.project(*dir);
      ASSERT_TRUE(again);
      EXPECT_LE(glm::length(*again - pixel), 1e-6) << pixel.x << ", " << pixel.y;
    }
  }
}

// COLMAP's models_test.cc checks, with its parameter sets: every (u, v, w) of its grid round
// trips through the image to (u/w, v/w) (COLMAP asks 1e-6, we 1e-9), every pixel of its
// 0..800 grid round trips back to itself (COLMAP skips fisheye pixels past 90°; every pixel
// here has either its ray or none, and the radial models refuse only what lies beyond the
// fold), and the principal point is the optical axis.
TEST(LensModelColmap, ItsPointsRoundTrip) {
  for (const LensCase& c : colmapCases()) {
    SCOPED_TRACE(c.label);
    const Lens lens = lensOf(c);
    for (int i = 0; i <= 10; ++i) {
      for (int j = 0; j <= 10; ++j) {
        const double u = -0.5 + 0.1 * i, v = -0.5 + 0.1 * j;
        for (const double w : {0.5, 1.0, 2.0}) {
          const std::optional<glm::dvec2> px = lens.project({u, v, w});
          ASSERT_TRUE(px);
          const std::optional<glm::dvec3> ray = lens.unproject(*px);
          ASSERT_TRUE(ray);
          EXPECT_NEAR(ray->x / ray->z, u / w, 1e-9);
          EXPECT_NEAR(ray->y / ray->z, v / w, 1e-9);
        }
      }
    }
    for (int x = 0; x <= 800; x += 50) {
      for (int y = 0; y <= 800; y += 50) {
        const std::optional<glm::dvec3> ray = lens.unproject({x, y});
        if (!ray) {
          const glm::dvec2 d((x - lens.cx()) / lens.fx(), (y - lens.cy()) / lens.fy());
          EXPECT_TRUE(hasNonRadialTerms(c) || glm::length(d) >= lens.validRegion().maxDistorted)
              << "pixel " << x << ", " << y << " refused";
          continue;
        }
        const std::optional<glm::dvec2> px = lens.project(*ray);
        ASSERT_TRUE(px);
        EXPECT_NEAR(px->x, x, 1e-6);
        EXPECT_NEAR(px->y, y, 1e-6);
      }
    }
    const std::optional<glm::dvec3> axis = lens.unproject({lens.cx(), lens.cy()});
    ASSERT_TRUE(axis);
    EXPECT_LT(angleBetween(*axis, {0, 0, 1}), 1e-15);
  }
}

// --- The valid region --------------------------------------------------------------------------

TEST(LensModelValidRegion, ClosedForms) {
  // SIMPLE_RADIAL k = −0.5: ρ = r − r³/2, ρ' = 1 − 1.5 r² = 0 at r = √(2/3), ρ = √(2/3)·2/3.
  LensValidRegion region = Lens(M::SimpleRadial, {500, 320, 240, -0.5}).validRegion();
  EXPECT_TRUE(region.bounded());
  EXPECT_NEAR(region.maxUndistorted, std::sqrt(2.0 / 3), 1e-12);
  EXPECT_NEAR(region.maxDistorted, std::sqrt(2.0 / 3) * 2 / 3, 1e-12);
  EXPECT_NE(region.text(false).find("r < 0.8165 (distorted 0.5443, 39.2° off-axis)"),
            std::string::npos)
      << region.text(false);
  // k = +0.5: ρ' = 1 + 1.5 r² > 0: no fold.
  EXPECT_FALSE(Lens(M::SimpleRadial, {500, 320, 240, 0.5}).validRegion().bounded());
  // OPENCV's fold is its radial polynomial's (tangential terms are checked per point).
  region = Lens(M::OpenCV, {500, 500, 320, 240, -0.5, 0, 0.01, -0.01}).validRegion();
  EXPECT_NEAR(region.maxUndistorted, std::sqrt(2.0 / 3), 1e-12);
  // RADIAL k1 = 0.1, k2 = −0.05: ρ' = 1 + 0.3 s − 0.25 s² = 0 at s = (0.3 + √1.09) / 0.5.
  region = Lens(M::Radial, {500, 320, 240, 0.1, -0.05}).validRegion();
  const double s = (0.3 + std::sqrt(1.09)) / 0.5;
  EXPECT_NEAR(region.maxUndistorted, std::sqrt(s), 1e-12);
  EXPECT_NEAR(region.maxDistorted, std::sqrt(s) * (1 + 0.1 * s - 0.05 * s * s), 1e-12);
  // FULL_OPENCV, k4 = 1: ρ = r / (1 + r²) folds at r = 1, ρ = 1/2 (a rational fold).
  region = Lens(M::FullOpenCV, {500, 500, 320, 240, 0, 0, 0, 0, 0, 1, 0, 0}).validRegion();
  EXPECT_NEAR(region.maxUndistorted, 1, 1e-12);
  EXPECT_NEAR(region.maxDistorted, 0.5, 1e-12);
  // FULL_OPENCV, k4 = −1: ρ = r / (1 − r²) rises to its pole at r = 1.
  region = Lens(M::FullOpenCV, {500, 500, 320, 240, 0, 0, 0, 0, 0, -1, 0, 0}).validRegion();
  EXPECT_NEAR(region.maxUndistorted, 1, 1e-12);
  EXPECT_LE(region.maxUndistorted, 1);
  EXPECT_GT(region.maxDistorted, 1e6);
  // SIMPLE_RADIAL_FISHEYE k = −0.1: ρ' = 1 − 0.3 θ² = 0 at θ = √(1/0.3) (104.6°).
  region = Lens(M::SimpleRadialFisheye, {300, 320, 240, -0.1}).validRegion();
  EXPECT_NEAR(region.maxUndistorted, std::sqrt(1 / 0.3), 1e-12);
  EXPECT_NEAR(region.maxDistorted, std::sqrt(1 / 0.3) * 2 / 3, 1e-12);
  EXPECT_NE(region.text(true).find("θ < 1.826 rad (distorted 1.217, 104.6° off-axis)"),
            std::string::npos)
      << region.text(true);
  // k = −0.01: the fold (θ = 5.77) lies beyond θ = π, which bounds every fisheye.
  region = Lens(M::SimpleRadialFisheye, {300, 320, 240, -0.01}).validRegion();
  EXPECT_EQ(region.maxUndistorted, kPi);
  EXPECT_NEAR(region.maxDistorted, kPi * (1 - 0.01 * kPi * kPi), 1e-12);
  region = Lens(M::OpenCVFisheye, {300, 300, 320, 240, 0, 0, 0, 0}).validRegion();
  EXPECT_EQ(region.maxUndistorted, kPi);
  EXPECT_EQ(region.maxDistorted, kPi);
  EXPECT_TRUE(region.bounded());
}

// The valid regions of COLMAP 4's models with formulas of their own (cameras/lens_formulas.h),
// against closed forms.
TEST(LensModelValidRegion, ClosedFormsOfTheFormulaModels) {
  // FOV ω = 0.9: ρ = atan(2 tan θ tan(ω/2)) / ω reaches π/(2ω) at θ = 90°.
  LensValidRegion region = Lens(M::FOV, {500, 500, 320, 240, 0.9}).validRegion();
  EXPECT_NEAR(region.maxUndistorted, kPi / 2, 1e-12);
  EXPECT_NEAR(region.maxDistorted, kPi / 1.8, 1e-12);
  EXPECT_NE(region.text(true).find("θ < 1.571 rad (distorted 1.745, 90.0° off-axis)"),
            std::string::npos)
      << region.text(true);
  // DIVISION k = 0.2: θ(ρ) = atan2(ρ, 1 + kρ²) peaks at ρ = 1/√k, tan θ = 1/(2√k). The
  // bisection resolves θ to the last bit; ρ, on a vertical tangent there, to its square root.
  region = Lens(M::Division, {500, 500, 320, 240, 0.2}).validRegion();
  EXPECT_NEAR(region.maxUndistorted, std::atan(1 / (2 * std::sqrt(0.2))), 1e-12);
  EXPECT_NEAR(region.maxDistorted, 1 / std::sqrt(0.2), 1e-7);
  // k = −0.3: every ρ has a ray, up to θ = 180° (the axis behind the camera).
  region = Lens(M::SimpleDivision, {500, 320, 240, -0.3}).validRegion();
  EXPECT_NEAR(region.maxUndistorted, kPi, 1e-12);
  EXPECT_GT(region.maxDistorted, 1e12);
  // EUCM α = 0.6, β = 1.1: COLMAP's inverse needs 1 − (2α − 1)βρ² >= 0, ρ <= 1/√(β(2α − 1)),
  // where its ray (ρ, m), m = (1 − α²βρ²) / (1 − α), points 133° off-axis.
  region = Lens(M::EUCM, {500, 500, 320, 240, 0.6, 1.1}).validRegion();
  const double rhoMax = 1 / std::sqrt(1.1 * 0.2);
  EXPECT_NEAR(region.maxDistorted, rhoMax, 1e-9);
  EXPECT_NEAR(region.maxUndistorted, std::atan2(rhoMax, (1 - 0.36 * 1.1 * rhoMax * rhoMax) / 0.4),
              1e-6);
  // α = 0.3, β = 0.8: the divisor α√(β sin²θ + cos²θ) + (1 − α) cos θ vanishes at
  // tan²θ = (1 − 2α)/(α²β), past 90°; ρ grows without bound up to there.
  region = Lens(M::EUCM, {500, 500, 320, 240, 0.3, 0.8}).validRegion();
  EXPECT_NEAR(region.maxUndistorted, kPi - std::atan(std::sqrt(0.4 / (0.09 * 0.8))), 1e-12);
  EXPECT_GT(region.maxDistorted, 1e6);
  // The equidistant fisheyes see up to 180°: ρ = θ.
  region = Lens(M::SimpleFisheye, {300, 320, 240}).validRegion();
  EXPECT_EQ(region.maxUndistorted, kPi);
  EXPECT_EQ(region.maxDistorted, kPi);
  // EQUIRECTANGULAR: every pixel, the whole sphere.
  EXPECT_FALSE(Lens(M::Equirectangular, {400, 200}).validRegion().bounded());
}

// EQUIRECTANGULAR in closed form: the centre looks along +z, a quarter of the width to the left
// along −x, the top row's centre near −y (up), the left and right edges along −z.
TEST(LensModelClosedForm, EquirectangularPixelsAndRays) {
  const Lens lens(M::Equirectangular, {400, 200});
  EXPECT_DOUBLE_EQ(lens.fx(), 400 / (2 * kPi));
  EXPECT_DOUBLE_EQ(lens.cy(), 100);
  const auto ray = [&](double x, double y) { return *lens.unproject({x, y}); };
  EXPECT_LT(glm::length(ray(200, 100) - glm::dvec3(0, 0, 1)), 1e-15);
  EXPECT_LT(glm::length(ray(100, 100) - glm::dvec3(-1, 0, 0)), 1e-15);
  EXPECT_LT(glm::length(ray(300, 100) - glm::dvec3(1, 0, 0)), 1e-15);
  EXPECT_LT(glm::length(ray(0, 100) - glm::dvec3(0, 0, -1)), 1e-15);
  EXPECT_LT(glm::length(ray(200, 0) - glm::dvec3(0, -1, 0)), 1e-15);
  EXPECT_LT(glm::length(ray(200, 50) - glm::normalize(glm::dvec3(0, -1, 1))), 1e-15);
  // Every pixel centre has its ray, and it projects back onto the centre.
  for (int i = 0; i < 200; i += 7)
    for (int j = 0; j < 400; j += 7) {
      const glm::dvec2 centre(j + 0.5, i + 0.5);
      const std::optional<glm::dvec3> dir = lens.unproject(centre);
      ASSERT_TRUE(dir);
      EXPECT_LE(glm::length(*lens.project(*dir) - centre), 1e-9);
    }
  EXPECT_FALSE(lens.project({0, 0, 0}));
  EXPECT_NE(errorOf([] { Lens(M::Equirectangular, {400, 0}); }).find("h = 0"), std::string::npos);
}

// Just inside the fold converges to the right point; just outside is refused, by undistort,
// unproject and project alike.
TEST(LensModelValidRegion, InsideConvergesOutsideIsRefused) {
  for (const LensCase& c : allCases()) {
    const Lens lens = lensOf(c);
    const LensValidRegion& region = lens.validRegion();
    if (!region.bounded()) continue;
    SCOPED_TRACE(c.label);
    const double R = region.maxUndistorted, D = region.maxDistorted;
    // At a pole of FULL_OPENCV's rational gain the forward map itself loses digits as
    // 1/(1 − r/R): "just inside" is 1e-3 there (the distorted radius is already ~1e3·R).
    const bool pole = D > 1e6;
    for (int k = 0; k < 16; ++k) {
      const glm::dvec2 azimuth(std::cos(k * kPi / 8 + 0.1), std::sin(k * kPi / 8 + 0.1));
      // Undistorted side.
      const glm::dvec2 inside = azimuth * (R * (1 - (pole ? 1e-3 : 1e-6)));
      glm::dmat2 jacobian;
      const glm::dvec2 d = lens.distort(inside, &jacobian);
      if (glm::determinant(jacobian) > 0) {
        EXPECT_TRUE(lens.project(directionOf(lens, inside)));
        const std::optional<glm::dvec2> x = lens.undistort(d);
        ASSERT_TRUE(x);
        EXPECT_LE(glm::length(lens.distort(*x) - d), 1e-9 * std::max(1.0, glm::length(d)));
      }
      if (R * (1 + 1e-6) < (lens.overTheta() ? kPi : 1e300)) {
        EXPECT_FALSE(lens.project(directionOf(lens, azimuth * (R * (1 + 1e-6)))));
      }
      // Distorted side (radial models: the fold is a circle of radius D there).
      if (hasNonRadialTerms(c) || pole) continue;
      const std::optional<glm::dvec2> in = lens.undistort(azimuth * (D * (1 - 1e-6)));
      ASSERT_TRUE(in);
      EXPECT_LT(glm::length(*in), R);
      // Where the fold is a vertical tangent (DIVISION with k > 0: ρ' → ∞ there), θ's last
      // bit moves ρ by ρ'·1e-16: the tolerance follows ρ'.
      glm::dmat2 atIn;
      lens.distort(*in, &atIn);
      const glm::dvec2 n = glm::normalize(*in);
      EXPECT_NEAR(glm::length(lens.distort(*in)), D * (1 - 1e-6),
                  std::max(1e-12, 1e-15 * glm::dot(n, atIn * n)));
      EXPECT_FALSE(lens.undistort(azimuth * (D * (1 + 1e-6))));
      const glm::dvec2 centre(lens.cx(), lens.cy()), scale(lens.fx(), lens.fy());
      EXPECT_TRUE(lens.unproject(centre + scale * azimuth * (D * (1 - 1e-6))));
      EXPECT_FALSE(lens.unproject(centre + scale * azimuth * (D * (1 + 1e-6))));
    }
  }
}

// Tangential and thin-prism terms fold the map in 2D as well. Over a grid reaching far past
// the fold, every point the inverse accepts is a true preimage on the unfolded side; the
// others get nothing. Never a garbage ray.
TEST(LensModelValidRegion, NoGarbageBeyondTheFold) {
  const std::vector<LensCase> cases = {
      {"OPENCV strong tangential", M::OpenCV, {500, 500, 0, 0, -0.3, 0.02, 0.05, -0.04}},
      {"THIN_PRISM_FISHEYE strong prism",
       M::ThinPrismFisheye,
       {300, 300, 0, 0, -0.05, 0.001, 0.02, 0.01, 0, 0, 0.05, -0.04}},
      {"SIMPLE_RADIAL k=-0.5", M::SimpleRadial, {500, 0, 0, -0.5}},
  };
  for (const LensCase& c : cases) {
    SCOPED_TRACE(c.label);
    const Lens lens = lensOf(c);
    int accepted = 0, refused = 0;
    for (int i = -60; i <= 60; ++i) {
      for (int j = -60; j <= 60; ++j) {
        const glm::dvec2 d(0.05 * i + 0.001, 0.05 * j);
        const std::optional<glm::dvec2> x = lens.undistort(d);
        if (!x) {
          ++refused;
          continue;
        }
        ++accepted;
        glm::dmat2 jacobian;
        EXPECT_LE(glm::length(lens.distort(*x, &jacobian) - d),
                  1e-9 * std::max(1.0, glm::length(d)));
        EXPECT_GT(glm::determinant(jacobian), 0);
        EXPECT_LT(glm::length(*x), lens.validRegion().maxUndistorted);
        // The same through pixels (these lenses have fx = fy and the principal point at 0).
        const glm::dvec2 pixel = d * lens.fx();
        const std::optional<glm::dvec3> ray = lens.unproject(pixel);
        ASSERT_TRUE(ray);
        const std::optional<glm::dvec2> back = lens.project(*ray);
        ASSERT_TRUE(back);
        EXPECT_LE(glm::length(*back - pixel), 1e-6);
      }
    }
    EXPECT_GT(accepted, 100);
    EXPECT_GT(refused, 100);
    // Inside the radial fold, strong tangential terms fold the map already (det J < 0): the
    // images of those points come back as their other, unfolded preimage or as nothing, and
    // the points themselves do not project.
    const double R = lens.validRegion().maxUndistorted;
    int folded = 0;
    for (int i = -40; i <= 40; ++i) {
      for (int j = -40; j <= 40; ++j) {
        const glm::dvec2 u = glm::dvec2(i, j) * (R / 40);
        glm::dmat2 jacobian;
        const glm::dvec2 d = lens.distort(u, &jacobian);
        if (!(glm::length(u) < R) || glm::determinant(jacobian) > 0) continue;
        ++folded;
        EXPECT_FALSE(lens.project(directionOf(lens, u)));
        const std::optional<glm::dvec2> x = lens.undistort(d);
        if (!x) continue;
        lens.distort(*x, &jacobian);
        EXPECT_GT(glm::determinant(jacobian), 0) << u.x << ", " << u.y;
      }
    }
    if (hasNonRadialTerms(c)) {
      EXPECT_GT(folded, 0);
    }
  }
}

// --- Extremes ----------------------------------------------------------------------------------

// A 190° fisheye: OPENCV_FISHEYE with zero coefficients is equidistant, r = f·θ. A 2000-pixel
// square image with θ = 95° at the edge of its inscribed circle.
TEST(LensModelExtremes, Fisheye190Degrees) {
  const double f = 1000 / (95 * kDeg);
  const Lens lens(M::OpenCVFisheye, {f, f, 1000, 1000, 0, 0, 0, 0});
  for (int column = 0; column < 2000; ++column) {
    const glm::dvec2 pixel(column + 0.5, 1000.0 + 1e-3 * column);  // a little off the row
    const std::optional<glm::dvec3> ray = lens.unproject(pixel);
    ASSERT_TRUE(ray) << column;
    const glm::dvec2 offset = pixel - glm::dvec2(1000, 1000);
    const double theta = glm::length(offset) / f;
    EXPECT_NEAR(angleBetween(*ray, {0, 0, 1}), theta, 1e-12) << column;
    EXPECT_NEAR(ray->z, std::cos(theta), 1e-12);  // past 90°: z < 0, never (u, v, 1)
    EXPECT_NEAR(std::atan2(ray->y, ray->x), std::atan2(offset.y, offset.x), 1e-9);
  }
  const std::optional<glm::dvec3> edge = lens.unproject({0.5, 1000});
  ASSERT_TRUE(edge);
  EXPECT_LT(edge->z, 0);
  EXPECT_GT(angleBetween(*edge, {0, 0, 1}), 94.9 * kDeg);
  // Forward: the ray 95° off-axis along −y lands on the image's top edge.
  const std::optional<glm::dvec2> top =
      lens.project({0, -std::sin(95 * kDeg), std::cos(95 * kDeg)});
  ASSERT_TRUE(top);
  EXPECT_NEAR(top->x, 1000, 1e-9);
  EXPECT_NEAR(top->y, 0, 1e-9);
  // Straight back (θ = π) has no pixel; a pixel past θ = π has no ray.
  EXPECT_FALSE(lens.project({0, 0, -1}));
  EXPECT_FALSE(lens.unproject({1000 + f * kPi * 1.0001, 1000}));
  // With distortion (COLMAP's OPENCV_FISHEYE coefficients) past 90° too.
  const Lens distorted(M::OpenCVFisheye, {f, f, 1000, 1000, -0.471, 0.223, -0.001, 0.001});
  for (double deg = 80; deg <= 95; deg += 0.5) {
    const glm::dvec3 dir(std::sin(deg * kDeg) * 0.6, std::sin(deg * kDeg) * 0.8,
                         std::cos(deg * kDeg));
    const std::optional<glm::dvec2> px = distorted.project(dir);
    ASSERT_TRUE(px);
    const std::optional<glm::dvec3> back = distorted.unproject(*px);
    ASSERT_TRUE(back);
    EXPECT_LT(angleBetween(*back, dir), 1e-12) << deg;
  }
}

TEST(LensModelExtremes, PrincipalPointOutsideTheImage) {
  for (const Lens& lens : {Lens(M::SimpleRadial, {800, -300, 1500, 0.05}),
                           Lens(M::OpenCV, {800, 820, 1000, -300, 0.1, -0.02, 0.001, 0.002}),
                           Lens(M::RadialFisheye, {600, -100, 900, -0.03, 0.001})}) {
    SCOPED_TRACE(lens.info().name);
    int unprojected = 0;
    for (int y = 0; y < 480; y += 16) {
      for (int x = 0; x < 640; x += 16) {
        const glm::dvec2 pixel(x + 0.5, y + 0.5);
        const std::optional<glm::dvec3> ray = lens.unproject(pixel);
        if (!ray) continue;
        ++unprojected;
        const std::optional<glm::dvec2> back = lens.project(*ray);
        ASSERT_TRUE(back);
        EXPECT_LE(glm::length(*back - pixel), 1e-6);
      }
    }
    EXPECT_EQ(unprojected, 40 * 30);
    const std::optional<glm::dvec3> axis = lens.unproject({lens.cx(), lens.cy()});
    ASSERT_TRUE(axis);
    EXPECT_LT(angleBetween(*axis, {0, 0, 1}), 1e-15);
  }
}

TEST(LensModelExtremes, FocalLengthsFrom10To1e6Pixels) {
  for (const double f : {10.0, 1e3, 1e6}) {
    for (const Lens& lens :
         {Lens(M::OpenCV, {f, f, 960, 540, -0.471, 0.223, -0.001, 0.001}),
          Lens(M::SimpleRadial, {f, 960, 540, 0.5}),
          Lens(M::OpenCVFisheye, {f, f, 960, 540, -0.05, 0.01, 0, 0}),
          Lens(M::FullOpenCV, {f, f, 960, 540, -0.1, 0.01, 0.001, -0.001, 0, 0.02, 0, 0})}) {
      SCOPED_TRACE(std::string(lens.info().name) + " f=" + std::to_string(f));
      int unprojected = 0, total = 0;
      for (int y = 0; y < 1080; y += 27) {
        for (int x = 0; x < 1920; x += 48) {
          const glm::dvec2 pixel(x + 0.5, y + 0.5);
          ++total;
          const std::optional<glm::dvec3> ray = lens.unproject(pixel);
          if (!ray) continue;
          ++unprojected;
          const std::optional<glm::dvec2> back = lens.project(*ray);
          ASSERT_TRUE(back);
          EXPECT_LE(glm::length(*back - pixel), 1e-6) << pixel.x << ", " << pixel.y;
        }
      }
      // Long focal lengths see the whole image; at 10 px the fisheye sees up to θ = π only.
      if (f >= 1e3) {
        EXPECT_EQ(unprojected, total);
      }
      EXPECT_GT(unprojected, 0);
    }
  }
}

// A whole image's direction table, as the renderer builds it once per camera: every pixel of a
// strongly distorted OPENCV lens either has its ray (which projects back onto the pixel) or
// none, and the fold's circle separates the two.
TEST(LensModelExtremes, DirectionTableOfAWholeImage) {
  const Lens lens(M::OpenCV, {700, 700, 480, 270, -0.5, 0.02, 0.002, -0.001});
  int missing = 0;
  for (int i = 0; i < 540; ++i) {
    for (int j = 0; j < 960; ++j) {
      const glm::dvec2 pixel(j + 0.5, i + 0.5);
      const std::optional<glm::dvec3> ray = lens.unproject(pixel);
      if (!ray) {
        ++missing;
        continue;
      }
      const std::optional<glm::dvec2> back = lens.project(*ray);
      ASSERT_TRUE(back);
      ASSERT_LE(glm::length(*back - pixel), 1e-6) << pixel.x << ", " << pixel.y;
    }
  }
  // The fold at r ≈ 0.836 (distorted ≈ 0.552, 386 px) cuts off the image's corners only
  // (about 139000 pixels outside the circle).
  EXPECT_GT(missing, 0);
  EXPECT_LT(missing, 960 * 540 / 3);
}

// unprojectBatch solves up to Lens::kBatch pixels side by side, their Newton iterations in
// lockstep: each lane must get exactly unproject()'s ray (or none), whatever its neighbours do
// (converge sooner or later, halve their steps, have no ray at all). Every model and lens of
// allCases(), pixels scattered over and beyond the image in batches of every size 1-8.
TEST(LensModelBatch, EveryLaneIsUnprojectBitForBit) {
  std::mt19937_64 rng(20261126);
  int bounded = 0;  // lenses with a fold (or a fisheye's θ = π)
  for (const LensCase& c : allCases()) {
    SCOPED_TRACE(c.label);
    const Lens lens(c.model, c.params);
    const glm::dvec2 centre(lens.cx(), lens.cy());
    // Radii from 0.1 px to five times the fold's (or 5 f where nothing bounds the lens),
    // log-uniform, in random directions.
    const double reach =
        5 * lens.fx() *
        std::max(1.0, lens.validRegion().bounded() ? lens.validRegion().maxDistorted : 1.0);
    std::uniform_real_distribution<double> logRadius(std::log(0.1), std::log(reach)),
        azimuth(0, 2 * kPi);
    int withRay = 0, without = 0;
    for (int batch = 0; batch < 400; ++batch) {
      const int n = 1 + batch % Lens::kBatch;
      glm::dvec2 pixels[Lens::kBatch];
      for (int k = 0; k < n; ++k) {
        const double r = std::exp(logRadius(rng)), a = azimuth(rng);
        pixels[k] = centre + r * glm::dvec2(std::cos(a), std::sin(a));
      }
      glm::dvec3 dirs[Lens::kBatch];
      bool hasRay[Lens::kBatch];
      lens.unprojectBatch(n, pixels, dirs, hasRay);
      for (int k = 0; k < n; ++k) {
        const std::optional<glm::dvec3> alone = lens.unproject(pixels[k]);
        ASSERT_EQ(hasRay[k], alone.has_value()) << "lane " << k << " of " << n;
        if (!alone) {
          ++without;
          continue;
        }
        ++withRay;
        ASSERT_EQ(std::memcmp(&dirs[k], &*alone, sizeof(glm::dvec3)), 0)
            << "lane " << k << " of " << n << ": " << dirs[k].x << " " << dirs[k].y << " "
            << dirs[k].z << " against " << alone->x << " " << alone->y << " " << alone->z;
      }
    }
    EXPECT_GT(withRay, 0);
    if (lens.validRegion().bounded()) {
      ++bounded;
      EXPECT_GT(without, 0);  // past the fold: lanes without a ray beside lanes with one
    }
  }
  EXPECT_GE(bounded, 10);
}

}  // namespace
}  // namespace aperture
