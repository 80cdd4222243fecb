// Every camera model: packets against the scalar path (tails included), the projection's round
// trip, and the registry's list. The models' own closed forms are in test_perspective.cpp,
// test_parallel_projection.cpp, test_thinlens.cpp, test_equirect.cpp and test_fisheye.cpp.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/util/error.h"
#include "tests/camera_support.h"

namespace aperture {
namespace {

using test::make;
using test::PacketBuffer;

// ---------------------------------------------------------------------------------------
// Every camera: packets against the scalar path; projection round trip.

class EveryCamera : public ::testing::TestWithParam<std::tuple<int, int, int>> {};

TEST_P(EveryCamera, PacketsEqualTheScalarPathTailsIncluded) {
  const auto [cameraIndex, width, spp] = GetParam();
  CameraParams p = test::everyCamera()[cameraIndex];
  p.width = 13;  // not a multiple of any block width: tail lanes on the right and bottom
  p.height = 7;
  p.spp = spp;
  p = test::sizedCamera(p);
  const glm::dvec3 renderOrigin(-2.0, 0.5, 1.5);
  const auto cam = make(p, renderOrigin);
  int blockW, blockH;
  test::blockShape(width, blockW, blockH);
  int tails = 0;
  for (int s = 0; s < spp; ++s)
    for (int y0 = 0; y0 < p.height; y0 += blockH)
      for (int x0 = 0; x0 < p.width; x0 += blockW) {
        PacketBuffer buf(width);
        int valid[16];
        const PacketRequest req{x0, y0, blockW, blockH, s};
        cam->generate(req, buf.lanes(), valid);
        const RayLanes& l = buf.lanes();
        for (int k = 0; k < width; ++k) {
          const int i = req.pixel(k).row, j = req.pixel(k).column;
          double x, y, lx = 0.5, ly = 0.5;
          cam->samplePosition(i, j, s, x, y);
          if (p.apertureRadius > 0) cam->lensSample(i, j, s, lx, ly);
          glm::dvec3 org, dir;
          const bool has = cam->ray(x, y, lx, ly, org, dir);
          const bool inImage = req.inImage(k, p.width, p.height);
          tails += !inImage;
          ASSERT_EQ(valid[k], (has && inImage) ? -1 : 0) << "lane " << k;
          ASSERT_EQ(l.orgX[k], float(org.x));
          ASSERT_EQ(l.orgY[k], float(org.y));
          ASSERT_EQ(l.orgZ[k], float(org.z));
          ASSERT_EQ(l.dirX[k], float(dir.x));
          ASSERT_EQ(l.dirY[k], float(dir.y));
          ASSERT_EQ(l.dirZ[k], float(dir.z));
          ASSERT_NO_FATAL_FAILURE(test::assertFixedLaneFields(l, k));
          ASSERT_NEAR(glm::length(dir), 1.0, 1e-14);
        }
      }
  if (width > 1) {
    EXPECT_GT(tails, 0);
  }
}

class EveryCameraProjection : public ::testing::TestWithParam<int> {};

TEST_P(EveryCameraProjection, ProjectInvertsTheRay) {
  CameraParams p = test::everyCamera()[GetParam()];
  p.width = 120;
  p.height = 80;
  p = test::sizedCamera(p);
  const auto cam = make(p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(0.0, 120.0), uy(0.0, 80.0), ut(0.5, 20.0);
  for (int n = 0; n < 500; ++n) {
    const double x = ux(rng), y = uy(rng);
    glm::dvec3 org, dir;
    if (!cam->ray(x, y, 0.5, 0.5, org, dir)) continue;
    const auto r = cam->project(org + ut(rng) * dir);
    ASSERT_TRUE(r) << x << "," << y;
    ASSERT_NEAR(r->x, x, 1e-6);
    ASSERT_NEAR(r->y, y, 1e-6);
  }
}

std::string everyName(const ::testing::TestParamInfo<std::tuple<int, int, int>>& info) {
  const auto [c, w, s] = info.param;
  const CameraParams p = test::everyCamera()[c];
  return p.type + std::to_string(c) + "_w" + std::to_string(w) + "_spp" + std::to_string(s);
}

INSTANTIATE_TEST_SUITE_P(Sweep, EveryCamera,
                         ::testing::Combine(::testing::Range(0, int(test::everyCamera().size())),
                                            ::testing::Values(1, 4, 8, 16),
                                            ::testing::Values(1, 4)),
                         everyName);

INSTANTIATE_TEST_SUITE_P(Sweep, EveryCameraProjection,
                         ::testing::Range(0, int(test::everyCamera().size())));

TEST(CameraRegistry, ListsEveryModelAndRejectsUnknownNames) {
  const std::vector<std::string> expected = {"perspective", "orthographic", "oblique",   "thinlens",
                                             "equirect",    "fisheye",      "calibrated"};
  EXPECT_EQ(cameraTypeNames(), expected);
  CameraParams p;
  p.type = "nope";
  try {
    makeCamera(p);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("fisheye"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace aperture
