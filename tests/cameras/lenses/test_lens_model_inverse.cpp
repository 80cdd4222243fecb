// COLMAP's lens models, their inverse (the rest is in test_lens_model.cpp): the inverse by
// Newton's method (round trips in normalised coordinates and in pixels, COLMAP's own points), the
// valid region against closed forms and at its boundary, extremes (a 190° fisheye, principal
// points outside the image, focal lengths from 10 px to 1e6 px, a whole image's direction
// table) and the batched inverse against the scalar one, lane by lane.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "cameras/lenses/lens_model.h"
#include "core/util/units.h"
#include "tests/camera_support.h"
#include "tests/lens_support.h"
#include "tests/numerics_support.h"

namespace aperture {
namespace {

using M = LensModelId;
using test::allCases;
using test::angleBetween;
using test::colmapCases;
using test::directionOf;
using test::hasNonRadialTerms;
using test::kDeg;
using test::LensCase;
using test::lensOf;
using test::randomInDisc;
using test::sampleRadius;

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
