// The thin lens camera in closed form: the rays of a pixel meet on the focus plane, aperture 0
// is the pinhole bit for bit, samples are stratified and deterministic, bad parameters throw.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/glm.hpp>
#include <vector>

#include "cameras/models/base.h"
#include "core/util/error.h"
#include "tests/camera_support.h"

namespace aperture {
namespace {

using test::make;
using test::PacketBuffer;
using test::toDouble;

struct ThinLensCase {
  double radius, focus;
};
class ThinLens : public ::testing::TestWithParam<ThinLensCase> {};

TEST_P(ThinLens, RaysOfAPixelMeetOnTheFocusPlane) {
  const ThinLensCase c = GetParam();
  CameraParams p = test::tiltedParams("thinlens");
  p.width = 64;
  p.height = 48;
  p.fovDeg = 45;
  p.apertureRadius = c.radius;
  p.focusDistance = c.focus;
  const glm::dvec3 renderOrigin(0.5, 0.25, -1.0);
  const auto cam = make(p, renderOrigin);
  const CameraFrame f = cam->frame();
  const glm::dvec3 eR = f.e - renderOrigin;
  auto focusHit = [&](const glm::dvec3& org, const glm::dvec3& dir) {
    const double depth0 = -glm::dot(org - eR, f.w), rate = -glm::dot(dir, f.w);
    return org + ((c.focus - depth0) / rate) * dir;
  };
  for (const glm::dvec2 raster :
       {glm::dvec2(32, 24), glm::dvec2(0.5, 0.5), glm::dvec2(63.9, 10.2), glm::dvec2(5, 47)}) {
    glm::dvec3 org0, dir0;
    cam->ray(raster.x, raster.y, 0.5, 0.5, org0, dir0);
    const glm::dvec3 target = focusHit(org0, dir0);
    for (int a = 0; a < 24; ++a)
      for (int b = 0; b < 24; ++b) {
        glm::dvec3 org, dir;
        cam->ray(raster.x, raster.y, (a + 0.5) / 24, (b + 0.37) / 24, org, dir);
        ASSERT_LE(glm::length(focusHit(org, dir) - target), 1e-5 * c.focus);
        // Rounded to float as in the packet. Float origins carry ~6e-8 of their distance
        // from the render origin (~4 here), amplified by the ray's slope, so this holds
        // only for focus distances well above that resolution.
        if (c.focus >= 0.5) {
          const glm::dvec3 orgF = toDouble(glm::vec3(org)), dirF = toDouble(glm::vec3(dir));
          ASSERT_LE(glm::length(focusHit(orgF, dirF) - target), 1e-5 * c.focus);
        }
        // The origin lies on the lens disk.
        ASSERT_LE(glm::length(org - eR), c.radius * (1 + 1e-12));
        ASSERT_LE(std::abs(glm::dot(org - eR, f.w)), 1e-12 * (c.radius + glm::length(eR)));
      }
  }
}

INSTANTIATE_TEST_SUITE_P(Sweep, ThinLens,
                         ::testing::Values(ThinLensCase{0.05, 0.5}, ThinLensCase{0.3, 7.0},
                                           ThinLensCase{1.0, 1000.0}, ThinLensCase{1e-9, 3.0},
                                           ThinLensCase{0.2, 1e-3}));

TEST(ThinLensCamera, ApertureZeroEqualsThePinholeBitForBit) {
  for (int spp : {1, 4, 9}) {
    CameraParams p = test::tiltedParams("perspective");
    p.width = 21;
    p.height = 13;
    p.fovDeg = 70;
    p.spp = spp;
    CameraParams t = p;
    t.type = "thinlens";
    t.apertureRadius = 0.0;
    t.focusDistance = 3.0;
    const glm::dvec3 renderOrigin(3.0, 2.0, 1.0);
    const auto pin = makeCamera(p, renderOrigin), lens = makeCamera(t, renderOrigin);
    for (int s = 0; s < spp; ++s)
      for (int y0 = 0; y0 < p.height; y0 += 4)
        for (int x0 = 0; x0 < p.width; x0 += 4) {
          PacketBuffer a(16), b(16);
          int va[16], vb[16];
          PacketRequest req{x0, y0, 4, 4, s};
          pin->generate(req, a.lanes(), va);
          lens->generate(req, b.lanes(), vb);
          for (int k = 0; k < 16; ++k) {
            ASSERT_EQ(std::memcmp(&a.lanes().dirX[k], &b.lanes().dirX[k], 4), 0);
            ASSERT_EQ(std::memcmp(&a.lanes().dirY[k], &b.lanes().dirY[k], 4), 0);
            ASSERT_EQ(std::memcmp(&a.lanes().dirZ[k], &b.lanes().dirZ[k], 4), 0);
            ASSERT_EQ(a.lanes().orgX[k], b.lanes().orgX[k]);
            ASSERT_EQ(a.lanes().orgY[k], b.lanes().orgY[k]);
            ASSERT_EQ(a.lanes().orgZ[k], b.lanes().orgZ[k]);
            ASSERT_EQ(va[k], vb[k]);
          }
        }
  }
}

TEST(ThinLensCamera, LensAndPixelSamplesAreStratifiedAndDeterministic) {
  CameraParams p = test::tiltedParams("thinlens");
  p.width = 8;
  p.height = 8;
  p.spp = 16;
  p.apertureRadius = 0.5;
  p.focusDistance = 2.0;
  const auto cam = make(p);
  for (int i : {0, 3, 7})
    for (int j : {0, 5}) {
      std::vector<int> lensStrata(16, 0), pixelStrata(16, 0);
      for (int s = 0; s < 16; ++s) {
        double lx, ly, x, y;
        cam->lensSample(i, j, s, lx, ly);
        cam->samplePosition(i, j, s, x, y);
        ++lensStrata[int(lx * 4) + 4 * int(ly * 4)];
        ++pixelStrata[int((x - j) * 4) + 4 * int((y - i) * 4)];
        double lx2, ly2;
        cam->lensSample(i, j, s, lx2, ly2);
        EXPECT_EQ(lx, lx2);
        EXPECT_EQ(ly, ly2);
      }
      for (int k = 0; k < 16; ++k) {
        EXPECT_EQ(lensStrata[k], 1) << "lens stratum " << k;
        EXPECT_EQ(pixelStrata[k], 1) << "pixel stratum " << k;
      }
    }
  // spp 1: the lens centre, so the single ray is the pinhole ray.
  p.spp = 1;
  const auto one = make(p);
  double lx, ly;
  one->lensSample(3, 4, 0, lx, ly);
  EXPECT_EQ(lx, 0.5);
  EXPECT_EQ(ly, 0.5);
}

TEST(ThinLensCamera, BadParametersThrow) {
  CameraParams p;
  p.type = "thinlens";
  p.apertureRadius = -0.1;
  EXPECT_THROW(makeCamera(p), Error);
  p.apertureRadius = 0.1;
  p.focusDistance = 0;
  EXPECT_THROW(makeCamera(p), Error);
  p.focusDistance = std::nan("");
  EXPECT_THROW(makeCamera(p), Error);
}

}  // namespace
}  // namespace aperture
