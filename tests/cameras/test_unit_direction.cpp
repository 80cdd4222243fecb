// The pinhole directions without a double √ or ÷ (cameras/unit_direction.h): the refined
// reciprocal length against a long-double reference, the unsure-rounding flag against values
// built next to float rounding points, and the perspective kernel against rayAt on millions
// of rays, the unsure ones among them.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "cameras/registry.h"
#include "cameras/unit_direction.h"
#include "tests/camera_support.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// The reference: float(p * (1 / √len2)) with a double √ and ÷ (PerspectiveCamera::rayAt).
float referenceComponent(double p, double len2) { return float(p * (1.0 / std::sqrt(len2))); }

/// The fast path: float(p * refinedInverseSqrt(len2)), and whether its rounding is unsure.
struct FastComponent {
  float value;
  bool unsure;
};
FastComponent fastComponent(double p, double len2) {
  const double x = p * refinedInverseSqrt(len2);
  return {float(x), !inverseSqrtInRange(len2) || unsureFloatRounding(x) != 0};
}

TEST(UnitDirection, RefinedInverseSqrtIsWithinFourRoundingsOfTheTrueValue) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> exponent(-30.0, 30.0);
  double worst = 0;
  for (int i = 0; i < 1000000; ++i) {
    const double len2 = std::pow(10.0, exponent(rng));
    ASSERT_TRUE(inverseSqrtInRange(len2));
    const long double truth = 1.0L / std::sqrt(static_cast<long double>(len2));
    const double rel = double(std::fabs((refinedInverseSqrt(len2) - truth) / truth));
    worst = std::max(worst, rel);
  }
  EXPECT_LE(worst, 4 * std::ldexp(1.0, -53));
  EXPECT_GT(worst, 0.0);  // a real approximation, not the reference in disguise
}

TEST(UnitDirection, InverseSqrtRangeExcludesWhatFloatCannotHold) {
  EXPECT_TRUE(inverseSqrtInRange(1.0));
  EXPECT_TRUE(inverseSqrtInRange(1e-30));
  EXPECT_TRUE(inverseSqrtInRange(1e30));
  EXPECT_FALSE(inverseSqrtInRange(1e-31));  // float(len2) leaves float's normal range
  EXPECT_FALSE(inverseSqrtInRange(1e39));   // float(len2) overflows
  EXPECT_FALSE(inverseSqrtInRange(std::nan("")));
}

// Values built within 160 units of a float midpoint, where the two computations can round
// apart: every lane the flag calls sure rounds as the reference, and some of the flagged
// lanes would not have (so a flag that trusted every lane fails this test).
TEST(UnitDirection, SureLanesRoundAsTheReferenceNextToFloatMidpoints) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> exponent(-6.0, 6.0), component(-1.0, 1.0);
  int unsure = 0, unsureAndDifferent = 0, sure = 0;
  for (int i = 0; i < 5000; ++i) {
    const double len2 = std::pow(10.0, exponent(rng));
    const float f = float(component(rng));
    const double midpoint = 0.5 * (double(f) + double(std::nextafter(f, 2.0f)));
    double p = midpoint * std::sqrt(len2);
    for (int k = 0; k < 160; ++k) p = std::nextafter(p, -1e300);
    for (int k = -160; k <= 160; ++k, p = std::nextafter(p, 1e300)) {
      const float want = referenceComponent(p, len2);
      const FastComponent got = fastComponent(p, len2);
      if (got.unsure) {
        ++unsure;
        unsureAndDifferent += got.value != want;
        continue;
      }
      ++sure;
      ASSERT_EQ(got.value, want) << "p " << p << " len2 " << len2;
    }
  }
  EXPECT_GT(sure, 0);
  EXPECT_GT(unsureAndDifferent, 0) << "no case where the flag mattered: " << unsure << " unsure";
}

// Away from crafted values the flag is rare: the fast path is the one that runs.
TEST(UnitDirection, FewerThanOneComponentInAHundredThousandIsUnsure) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> coordinate(-2.0, 2.0);
  int unsure = 0;
  const int n = 1000000;
  for (int i = 0; i < n; ++i) {
    const double px = coordinate(rng), py = coordinate(rng), pz = -1.0;
    const double len2 = (px * px + py * py) + pz * pz;
    unsure += fastComponent(px, len2).unsure;
  }
  EXPECT_LT(unsure, n / 100000);
}

// The perspective kernel against the scalar path (rayAt: one √ and ÷ a ray) on every pixel of
// large images from random poses, with at least one lane whose rounding was unsure: those
// blocks took the reference expressions and still match.
TEST(UnitDirection, PerspectiveKernelEqualsRayAtOnMillionsOfRaysTheUnsureIncluded) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> coordinate(-5.0, 5.0), fov(20.0, 120.0);
  int unsureRays = 0;
  for (int c = 0; c < 4; ++c) {
    const std::string flags =
        "--eye " + std::to_string(coordinate(rng)) + "," + std::to_string(coordinate(rng)) + "," +
        std::to_string(coordinate(rng)) + " --dir " + std::to_string(coordinate(rng)) + "," +
        std::to_string(coordinate(rng)) + ",-7 --fov " + std::to_string(fov(rng)) +
        " --size 2003,1501";
    const CameraParams p = test::cameraParamsFromFlags(flags);
    const auto cam = makeCameraModel(p, glm::dvec3(0.25, -0.5, 0.75));
    test::PacketBuffer buf(16);
    int valid[16];
    for (int y0 = 0; y0 < p.height; y0 += 4)
      for (int x0 = 0; x0 < p.width; x0 += 4) {
        const PacketRequest req{x0, y0, 4, 4, 0};
        cam->generate(req, buf.lanes(), valid);
        const RayLanes& l = buf.lanes();
        for (int k = 0; k < 16; ++k) {
          if (!req.inImage(k, p.width, p.height)) continue;
          const int i = req.pixel(k).row, j = req.pixel(k).column;
          double x, y;
          cam->samplePosition(i, j, 0, x, y);
          glm::dvec3 org, dir;
          ASSERT_TRUE(cam->ray(x, y, 0.5, 0.5, org, dir));
          ASSERT_EQ(l.dirX[k], float(dir.x)) << flags << " pixel " << i << "," << j;
          ASSERT_EQ(l.dirY[k], float(dir.y)) << flags << " pixel " << i << "," << j;
          ASSERT_EQ(l.dirZ[k], float(dir.z)) << flags << " pixel " << i << "," << j;
          // Rays next to a float rounding point, judged on the reference's double (the
          // kernel judges its own, at most 8 units away, so the counts may differ slightly).
          unsureRays += (unsureFloatRounding(dir.x) | unsureFloatRounding(dir.y) |
                         unsureFloatRounding(dir.z)) != 0;
        }
      }
  }
  EXPECT_GT(unsureRays, 0) << "no unsure lane: the fallback went untested";
}

// Pixels whose direction the fast path alone rounds differently from rayAt (about one ray in
// 10^9): found by running the kernel without its fallback over random 1920x1080 cameras until
// four turned up. Their blocks must take the reference expressions; without the fallback this
// test fails.
TEST(UnitDirection, PixelsWhereOnlyTheFallbackRoundsAsRayAt) {
  struct Case {
    const char* flags;
    int row, column;
  };
  const Case cases[] = {
      {"--eye 1.310,4.258,-1.816 --dir -4.915,4.986,-7 --fov 33.42", 539, 67},
      {"--eye -3.273,-0.031,1.228 --dir 2.676,-3.274,-7 --fov 50.49", 906, 1703},
      {"--eye 3.376,-2.920,0.936 --dir 4.030,-1.163,-7 --fov 94.62", 262, 79},
      {"--eye -0.419,1.791,-0.554 --dir -1.661,3.702,-7 --fov 114.11", 654, 814},
  };
  for (const Case& c : cases) {
    const CameraParams p = test::cameraParamsFromFlags(std::string(c.flags) + " --size 1920,1080");
    const auto cam = makeCameraModel(p, glm::dvec3(0.0));
    test::PacketBuffer buf(16);
    int valid[16];
    const PacketRequest req{c.column / 4 * 4, c.row / 4 * 4, 4, 4, 0};
    cam->generate(req, buf.lanes(), valid);
    const RayLanes& l = buf.lanes();
    for (int k = 0; k < 16; ++k) {
      double x, y;
      cam->samplePosition(req.pixel(k).row, req.pixel(k).column, 0, x, y);
      glm::dvec3 org, dir;
      ASSERT_TRUE(cam->ray(x, y, 0.5, 0.5, org, dir));
      EXPECT_EQ(l.dirX[k], float(dir.x)) << c.flags << " lane " << k;
      EXPECT_EQ(l.dirY[k], float(dir.y)) << c.flags << " lane " << k;
      EXPECT_EQ(l.dirZ[k], float(dir.z)) << c.flags << " lane " << k;
    }
  }
}

}  // namespace
