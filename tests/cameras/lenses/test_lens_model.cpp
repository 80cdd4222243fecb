// COLMAP's lens models (issue 11): the model table against COLMAP's, the forward map against an
// independent reference written in this file straight from the formulas of COLMAP's
// src/colmap/sensor/models.h (and shown to catch wrong conventions), closed forms and the
// analytic Jacobian against finite differences. The inverse, the valid region, the extremes and
// the batched inverse are in test_lens_model_inverse.cpp; the parameter sets (COLMAP's own, from
// src/colmap/sensor/models_test.cc, and harder ones) in tests/lens_support.h.
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
#include "tests/lens_support.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using M = LensModelId;
using test::allCases;
using test::angleBetween;
using test::colmapCases;
using test::directionOf;
using test::errorOf;
using test::extremeCases;
using test::hasNonRadialTerms;
using test::kDeg;
using test::LensCase;
using test::lensOf;
using test::randomInDisc;
using test::sampleRadius;

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

}  // namespace
}  // namespace aperture
