// View volumes: points inside project into the image, points just outside do not; the box
// test is conservative for every ray of the camera.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cameras/geometry/view_volume.h"
#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/util/error.h"
#include "tests/camera_support.h"

namespace aperture {
namespace {

bool inImage(const std::optional<glm::dvec2>& r, int w, int h) {
  return r && r->x >= 0 && r->x <= w && r->y >= 0 && r->y <= h;
}

glm::dvec3 fromCamera(const ViewVolume& vv, double x, double y, double z) {
  return vv.eye + x * vv.u + y * vv.v - z * vv.w;
}

class ViewVolumePlanar : public ::testing::TestWithParam<int> {};

// Perspective (plain, shifted, architectural), orthographic and oblique: the volume is exactly
// the set of points that project into the image between near and far.
TEST_P(ViewVolumePlanar, InsidePointsProjectIntoTheImageOutsidePointsDoNot) {
  CameraParams p = test::everyCamera()[GetParam()];
  p.width = 96;
  p.height = 64;
  const auto cam = makeCameraModel(p);
  const double nearDist = 0.5, farDist = 30.0;
  const ViewVolume vv = cam->viewVolume(nearDist, farDist);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int n = 0; n < 2000; ++n) {
    const double z = nearDist + (farDist - nearDist) * unit(rng);
    const double x = vv.xLo.at(z) + (vv.xHi.at(z) - vv.xLo.at(z)) * unit(rng);
    const double y = vv.yLo.at(z) + (vv.yHi.at(z) - vv.yLo.at(z)) * unit(rng);
    const glm::dvec3 inside = fromCamera(vv, x, y, z);
    ASSERT_TRUE(vv.contains(inside));
    ASSERT_TRUE(inImage(cam->project(inside), p.width, p.height));
    ASSERT_TRUE(vv.mayIntersectBox(inside - 1e-3, inside + 1e-3));
    // Just outside, across each side: 1e-4 of the cross-section's width beyond the bound.
    const double ex = 1e-4 * (vv.xHi.at(z) - vv.xLo.at(z)),
                 ey = 1e-4 * (vv.yHi.at(z) - vv.yLo.at(z));
    for (const glm::dvec3& out :
         {fromCamera(vv, vv.xHi.at(z) + ex, y, z), fromCamera(vv, vv.xLo.at(z) - ex, y, z),
          fromCamera(vv, x, vv.yHi.at(z) + ey, z), fromCamera(vv, x, vv.yLo.at(z) - ey, z)}) {
      ASSERT_FALSE(vv.contains(out));
      ASSERT_FALSE(inImage(cam->project(out), p.width, p.height));
    }
    ASSERT_FALSE(vv.contains(fromCamera(vv, x, y, farDist * 1.001)));
  }
  // The corners project onto the image corners.
  const glm::dvec2 imageCorners[4] = {
      {0, double(p.height)}, {double(p.width), double(p.height)}, {double(p.width), 0}, {0, 0}};
  for (int c = 0; c < 8; ++c) {
    const auto r = cam->project(vv.corners[c]);
    ASSERT_TRUE(r);
    EXPECT_NEAR(r->x, imageCorners[c % 4].x, 1e-6 * p.width) << c;
    EXPECT_NEAR(r->y, imageCorners[c % 4].y, 1e-6 * p.height) << c;
  }
  // A box well outside is culled; one straddling a side is not.
  const glm::dvec3 farOut = fromCamera(vv, vv.xHi.at(10) + 5, 0, 10);
  EXPECT_FALSE(vv.mayIntersectBox(farOut - 0.5, farOut + 0.5));
  const glm::dvec3 edge = fromCamera(vv, vv.xHi.at(10), 0.5 * (vv.yLo.at(10) + vv.yHi.at(10)), 10);
  EXPECT_TRUE(vv.mayIntersectBox(edge + 0.1 * vv.u - 0.2, edge + 0.1 * vv.u + 0.2));
  EXPECT_FALSE(vv.mayIntersectBox(cam->frame().e + 100.0 * cam->frame().w - 1.0,
                                  cam->frame().e + 100.0 * cam->frame().w + 1.0))
      << "behind the camera";
}

// Indices into everyCamera(): perspective, shifted, architectural, orthographic, oblique.
INSTANTIATE_TEST_SUITE_P(Models, ViewVolumePlanar, ::testing::Values(0, 1, 2, 3, 4));

// Every camera: points on its rays between near and far lie in the volume and in any box
// around them, including the thin lens (sheared frustum) and an infinite far distance.
TEST(ViewVolume, ContainsEveryRayOfEveryCamera) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const CameraParams& base : test::everyCamera())
    for (double farDist : {25.0, double(INFINITY)}) {
      CameraParams p = base;
      p.width = 64;
      p.height = 48;
      p = test::sizedCamera(p);
      const auto cam = makeCameraModel(p);
      const double nearDist = 0.25;
      const ViewVolume vv = viewVolumeFor(p, nearDist, farDist);
      const bool planar = vv.kind != ViewVolume::Kind::AllSpace;
      const glm::dvec3 e = cam->frame().e, w = cam->frame().w;
      for (int n = 0; n < 3000; ++n) {
        glm::dvec3 org, dir;
        if (!cam->ray(p.width * unit(rng), p.height * unit(rng), unit(rng), unit(rng), org, dir))
          continue;
        // A depth (planar) or distance (panoramas) within [near, min(far, 40)].
        const double target = nearDist + (std::min(farDist, 40.0) - nearDist) * unit(rng);
        const double t = planar ? (target + glm::dot(org - e, w)) / -glm::dot(dir, w) : target;
        const glm::dvec3 point = org + t * dir;
        const glm::dvec3 q = planar ? point : e + target * dir;
        if (planar && t < 0) continue;
        ASSERT_TRUE(vv.contains(q) || vv.mayIntersectBox(q, q)) << p.type;
        ASSERT_TRUE(vv.mayIntersectBox(q - 1e-9, q + 1e-9)) << p.type;
      }
    }
}

TEST(ViewVolume, KindsAndDegenerateRanges) {
  const auto all = test::everyCamera();
  EXPECT_EQ(viewVolumeFor(all[0], 1, 10).kind, ViewVolume::Kind::Frustum);
  EXPECT_EQ(viewVolumeFor(all[3], 1, 10).kind, ViewVolume::Kind::Box);
  EXPECT_EQ(viewVolumeFor(all[4], 1, 10).kind, ViewVolume::Kind::Parallelepiped);
  EXPECT_EQ(viewVolumeFor(all[5], 1, 10).kind, ViewVolume::Kind::ShearedFrustum);
  EXPECT_EQ(viewVolumeFor(all[6], 1, 10).kind, ViewVolume::Kind::AllSpace);
  EXPECT_THROW(viewVolumeFor(all[0], -1, 10), Error);
  EXPECT_THROW(viewVolumeFor(all[0], 5, 1), Error);
  EXPECT_THROW(viewVolumeFor(all[0], std::nan(""), 1), Error);
  // A perspective volume with near 0 has its four near corners at the eye.
  const ViewVolume vv = viewVolumeFor(all[0], 0, 10);
  for (int c = 0; c < 4; ++c) EXPECT_LE(glm::length(vv.corners[c] - all[0].eye), 1e-12);
}

TEST(ViewVolume, FullSpherePanoramaSeesEveryPointOfTheShell) {
  CameraParams p = test::everyCamera()[6];
  p.width = 90;
  p.height = 45;
  const auto cam = makeCameraModel(p);
  const ViewVolume vv = cam->viewVolume(1.0, 5.0);
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  for (int n = 0; n < 2000; ++n) {
    const glm::dvec3 d = glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)));
    const glm::dvec3 inside = p.eye + 3.0 * d;
    ASSERT_TRUE(vv.contains(inside));
    ASSERT_TRUE(inImage(cam->project(inside), p.width, p.height));
    ASSERT_FALSE(vv.contains(p.eye + 5.001 * d));
    ASSERT_FALSE(vv.contains(p.eye + 0.999 * d));
  }
  EXPECT_FALSE(vv.mayIntersectBox(p.eye + 10.0, p.eye + 11.0));
  EXPECT_FALSE(vv.mayIntersectBox(p.eye - 0.1, p.eye + 0.1)) << "inside the near sphere";
  EXPECT_TRUE(vv.mayIntersectBox(p.eye - 4.0, p.eye + 4.0));
}

}  // namespace
}  // namespace aperture
