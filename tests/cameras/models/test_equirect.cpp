// The equirectangular panorama in closed form: directions against the spherical formula, bad
// ranges refused.
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

TEST(PanoramaCamera, EquirectDirectionsMatchTheSphericalFormula) {
  for (const auto& [lon, lat] : {std::pair{glm::dvec2(-180, 180), glm::dvec2(-90, 90)},
                                 std::pair{glm::dvec2(-60, 100), glm::dvec2(-30, 45)},
                                 std::pair{glm::dvec2(0, 360), glm::dvec2(-10, 10)}}) {
    CameraParams p = test::tiltedParams("equirect");
    p.width = 73;
    p.height = 37;
    p.longitudeRangeDeg = lon;
    p.latitudeRangeDeg = lat;
    const auto cam = make(p);
    const CameraFrame f = cam->frame();
    for (int i = 0; i < p.height; ++i)
      for (int j = 0; j < p.width; ++j) {
        const double phi = rad(lon.x + (j + 0.5) / p.width * (lon.y - lon.x));
        const double theta = rad(lat.y - (i + 0.5) / p.height * (lat.y - lat.x));
        const glm::dvec3 expected = std::cos(theta) * std::sin(phi) * f.u + std::sin(theta) * f.v -
                                    std::cos(theta) * std::cos(phi) * f.w;
        const Lane lane = pixelLane(*cam, i, j);
        ASSERT_LE(glm::length(toDouble(lane.dir) - expected), 1e-6) << i << "," << j;
        ASSERT_EQ(lane.valid, -1);
        ASSERT_EQ(lane.org, glm::vec3(p.eye));
      }
  }
}

TEST(PanoramaCamera, BadRangesThrow) {
  CameraParams p;
  p.type = "equirect";
  p.longitudeRangeDeg = {10, -10};
  EXPECT_THROW(makeCamera(p), Error);
  p.longitudeRangeDeg = {-200, 200};
  EXPECT_THROW(makeCamera(p), Error);
  p.longitudeRangeDeg = {-180, 180};
  p.latitudeRangeDeg = {-95, 0};
  EXPECT_THROW(makeCamera(p), Error);
  p.latitudeRangeDeg = {-90, 90};
  p.shift = {0.1, 0};
  EXPECT_THROW(makeCamera(p), Error);
}

}  // namespace
}  // namespace aperture
