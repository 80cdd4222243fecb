// Orthographic and oblique cameras in closed form: directions, origins on the image plane, the
// viewport they need and the directions they refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/glm.hpp>
#include <string>

#include "cameras/models/base.h"
#include "core/util/error.h"
#include "tests/camera_support.h"

namespace aperture {
namespace {

using test::Lane;
using test::make;
using test::pixelLane;
using test::rad;
using test::toDouble;

void checkParallel(const CameraParams& p, const glm::dvec3& expectedDir) {
  const double vw = p.viewport->x, vh = p.viewport->y;
  // Camera-relative, as with a mesh anchor near the camera: float origins then resolve the
  // viewport (their absolute rounding is ~6e-8 of their distance from the render origin).
  const glm::dvec3 renderOrigin = p.eye + glm::dvec3(0.3, -0.2, 0.1) * vw;
  const auto cam = make(p, renderOrigin);
  const CameraFrame f = cam->frame();
  const glm::vec3 dirF(expectedDir);
  const double tol = 1e-6 * std::max(vw, vh);
  for (int i = 0; i < p.height; ++i)
    for (int j = 0; j < p.width; ++j) {
      const Lane lane = pixelLane(*cam, i, j);
      ASSERT_EQ(lane.dir, dirF) << "pixel " << i << "," << j;
      const double u = ((j + 0.5) / p.width - 0.5) * vw, v = -((i + 0.5) / p.height - 0.5) * vh;
      const glm::dvec3 expectedOrg = f.e + u * f.u + v * f.v - renderOrigin;
      ASSERT_LE(glm::length(toDouble(lane.org) - expectedOrg), tol) << i << "," << j;
      // On the image plane through the eye.
      ASSERT_LE(std::abs(glm::dot(toDouble(lane.org) + renderOrigin - f.e, f.w)), tol);
      // Before rounding, the double origin matches the formula to double precision.
      glm::dvec3 org, dir;
      cam->ray(j + 0.5, i + 0.5, 0.5, 0.5, org, dir);
      ASSERT_LE(glm::length(org - expectedOrg), 1e-12 * (glm::length(p.eye) + vw + vh));
    }
}

TEST(OrthographicCamera, DirectionsAreMinusWAndOriginsOnTheImagePlane) {
  for (glm::dvec2 viewport : {glm::dvec2(4.0, 3.0), glm::dvec2(1e-4, 2e-4), glm::dvec2(1e6, 1e6)}) {
    CameraParams p = test::tiltedParams("orthographic");
    p.eye += glm::dvec3(100.0, -50.0, 20.0);
    p.at = *p.at + glm::dvec3(100.0, -50.0, 20.0);
    p.width = 23;
    p.height = 17;
    p.viewport = viewport;
    checkParallel(p, -CameraFrame::fromLookAt(p.eye, *p.at, p.up).w);
  }
}

TEST(OrthographicCamera, NeedsAViewport) {
  CameraParams p;
  p.type = "orthographic";
  p.fovDeg = 40;
  EXPECT_THROW(makeCamera(p), Error);
  p.viewport = glm::dvec2(2.0, 1.0);
  EXPECT_NO_THROW(makeCamera(p));
  p.shift = {0.1, 0.0};
  EXPECT_THROW(makeCamera(p), Error);
}

TEST(ObliqueCamera, AnglesGiveTheDocumentedDirection) {
  for (glm::dvec2 a : {glm::dvec2(30.0, 0.0), glm::dvec2(-15.0, 45.0), glm::dvec2(60.0, -60.0),
                       glm::dvec2(88.0, 0.0)}) {
    CameraParams p = test::tiltedParams("oblique");
    p.width = 19;
    p.height = 12;
    p.viewport = glm::dvec2(5.0, 3.0);
    p.obliqueAnglesDeg = a;
    const CameraFrame f = CameraFrame::fromLookAt(p.eye, *p.at, p.up);
    const glm::dvec3 g = -f.w + std::tan(rad(a.x)) * f.u + std::tan(rad(a.y)) * f.v;
    checkParallel(p, g / glm::length(g));
  }
}

TEST(ObliqueCamera, WorldDirectionIsUsedAsGiven) {
  CameraParams p = test::tiltedParams("oblique");
  p.width = 8;
  p.height = 8;
  p.viewport = glm::dvec2(2.0, 2.0);
  const CameraFrame f = CameraFrame::fromLookAt(p.eye, *p.at, p.up);
  const glm::dvec3 dir = -3.0 * f.w + 1.0 * f.u - 0.5 * f.v;
  p.obliqueDir = dir;
  checkParallel(p, dir / glm::length(dir));
}

TEST(ObliqueCamera, SteepOrBackwardDirectionsAreErrors) {
  CameraParams base;
  base.type = "oblique";
  base.viewport = glm::dvec2(2.0, 2.0);
  base.dir = glm::dvec3(0, 0, -1);
  auto withAngles = [&](double ax, double ay) {
    CameraParams p = base;
    p.obliqueAnglesDeg = glm::dvec2(ax, ay);
    return p;
  };
  auto withDir = [&](glm::dvec3 d) {
    CameraParams p = base;
    p.obliqueDir = d;
    return p;
  };
  EXPECT_THROW(makeCamera(base), Error) << "no direction";
  EXPECT_THROW(makeCamera(withAngles(89.0, 0.0)), Error);
  EXPECT_THROW(makeCamera(withAngles(0.0, -95.0)), Error);
  EXPECT_THROW(makeCamera(withAngles(88.9, 88.9)), Error) << "combined angle above 89";
  EXPECT_THROW(makeCamera(withAngles(std::nan(""), 0.0)), Error);
  EXPECT_THROW(makeCamera(withDir({0, 0, 1})), Error) << "backwards";
  EXPECT_THROW(makeCamera(withDir({1, 0, 0})), Error) << "perpendicular";
  EXPECT_THROW(makeCamera(withDir({1, 0, -std::tan(rad(0.9))})), Error) << "89.1 degrees";
  EXPECT_THROW(makeCamera(withDir({0, 0, 0})), Error);
  EXPECT_NO_THROW(makeCamera(withAngles(88.9, 0.0)));
  EXPECT_NO_THROW(makeCamera(withDir({1, 0, -std::tan(rad(1.1))})));
}

}  // namespace
}  // namespace aperture
