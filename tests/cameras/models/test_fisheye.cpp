// The fisheye camera in closed form: directions against the equidistant formula, outside the
// image circle a miss, a field of view out of range refused.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/glm.hpp>
#include <string>

#include "cameras/models/base.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "tests/camera_support.h"

namespace aperture {
namespace {

using test::Lane;
using test::make;
using test::pixelLane;
using test::rad;
using test::toDouble;

TEST(FisheyeCamera, DirectionsMatchTheEquidistantFormulaAndOutsideIsAMiss) {
  for (double fov : {90.0, 180.0, 250.0, 360.0})
    for (const auto& [w, h] : {std::pair{41, 41}, std::pair{64, 40}}) {
      CameraParams p = test::tiltedParams("fisheye");
      p.width = w;
      p.height = h;
      p.fisheyeFovDeg = fov;
      const auto cam = make(p);
      const CameraFrame f = cam->frame();
      const double radius = 0.5 * std::min(w, h);
      int inside = 0;
      for (int i = 0; i < h; ++i)
        for (int j = 0; j < w; ++j) {
          const double a = (j + 0.5 - 0.5 * w) / radius, b = (0.5 * h - (i + 0.5)) / radius;
          const double rho = std::hypot(a, b);
          const Lane lane = pixelLane(*cam, i, j);
          ASSERT_TRUE(std::isfinite(lane.dir.x) && std::isfinite(lane.dir.y) &&
                      std::isfinite(lane.dir.z));
          if (rho > 1) {
            ASSERT_EQ(lane.valid, 0) << i << "," << j;
            continue;
          }
          ++inside;
          const double theta = rho * rad(fov) / 2;
          const glm::dvec3 expected =
              rho == 0 ? -f.w
                       : std::sin(theta) * (a / rho * f.u + b / rho * f.v) - std::cos(theta) * f.w;
          ASSERT_EQ(lane.valid, -1);
          ASSERT_LE(glm::length(toDouble(lane.dir) - expected), 1e-6) << i << "," << j;
        }
      EXPECT_NEAR(inside, kPi * radius * radius, 4 * radius);
    }
}

TEST(FisheyeCamera, FovOutOfRangeThrows) {
  CameraParams p;
  p.type = "fisheye";
  for (double fov : {0.0, -10.0, 360.5, std::nan("")}) {
    p.fisheyeFovDeg = fov;
    EXPECT_THROW(makeCamera(p), Error) << fov;
  }
}

}  // namespace
}  // namespace aperture
