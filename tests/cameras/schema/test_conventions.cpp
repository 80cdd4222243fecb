// Convention converters (cameras/schema/conventions.h) against hand-computed cases: pbrt's and
// Mitsuba's fov axes, Blender's sensor fit, OpenCV's intrinsics, a 35 mm lens's summary.
#include <gtest/gtest.h>

#include <cmath>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/conventions.h"
#include "core/util/error.h"

namespace aperture {
namespace {

void expectPlane(const ImagePlane& p, double vw, double vh, double sx = 0, double sy = 0) {
  EXPECT_NEAR(p.vw, vw, 1e-12);
  EXPECT_NEAR(p.vh, vh, 1e-12);
  EXPECT_NEAR(p.shift.x, sx, 1e-12);
  EXPECT_NEAR(p.shift.y, sy, 1e-12);
}

TEST(Conventions, PbrtFovSpansTheShorterAxis) {
  // tan(45°) = 1: the shorter extent is 2 at d = 1.
  expectPlane(fromPbrt(90, 200, 100), 4.0, 2.0);
  expectPlane(fromPbrt(90, 100, 200), 2.0, 4.0);
  expectPlane(fromPbrt(90, 100, 100, 3.0), 6.0, 6.0);
  EXPECT_THROW(fromPbrt(180, 10, 10), Error);
}

TEST(Conventions, MitsubaFovAxes) {
  expectPlane(fromMitsuba(90, MitsubaFovAxis::X, 200, 100), 2.0, 1.0);
  expectPlane(fromMitsuba(90, MitsubaFovAxis::Y, 200, 100), 4.0, 2.0);
  // Diagonal of 200 x 100 px is 100·√5: vw = 2·200/(100√5) = 4/√5.
  expectPlane(fromMitsuba(90, MitsubaFovAxis::Diagonal, 200, 100), 4.0 / std::sqrt(5.0),
              2.0 / std::sqrt(5.0));
  expectPlane(fromMitsuba(90, MitsubaFovAxis::Smaller, 200, 100), 4.0, 2.0);
  expectPlane(fromMitsuba(90, MitsubaFovAxis::Larger, 200, 100), 2.0, 1.0);
  expectPlane(fromMitsuba(90, MitsubaFovAxis::Smaller, 100, 200), 2.0, 4.0);
  EXPECT_EQ(parseMitsubaFovAxis("diagonal"), MitsubaFovAxis::Diagonal);
  EXPECT_THROW(parseMitsubaFovAxis("z"), Error);
}

TEST(Conventions, BlenderSensorFit) {
  // 50 mm on 36 x 24 mm: 36/50 = 0.72, 24/50 = 0.48.
  expectPlane(fromBlender(50, 36, 24, SensorFit::Auto, 1920, 1080), 0.72, 0.405);
  expectPlane(fromBlender(50, 36, 24, SensorFit::Auto, 1080, 1920), 0.405, 0.72);
  expectPlane(fromBlender(50, 36, 24, SensorFit::Horizontal, 1080, 1920), 0.72, 1.28);
  expectPlane(fromBlender(50, 36, 24, SensorFit::Vertical, 1920, 1080), 0.48 * 16 / 9, 0.48);
  EXPECT_EQ(parseBlenderSensorFit("VERTICAL"), SensorFit::Vertical);
  EXPECT_THROW(parseBlenderSensorFit("FILL"), Error);
  EXPECT_THROW(fromBlender(0, 36, 24, SensorFit::Auto, 10, 10), Error);
}

TEST(Conventions, OpenCVIntrinsics) {
  // Principal point at the exact centre in OpenCV's convention: (W − 1)/2, (H − 1)/2.
  expectPlane(fromOpenCV(500, 500, 319.5, 239.5, 640, 480), 1.28, 0.96);
  // cx 10 px right of centre: the axis is at raster 330, so the window moves left by 10/640.
  expectPlane(fromOpenCV(500, 500, 329.5, 239.5, 640, 480), 1.28, 0.96, -10.0 / 640);
  // cy 20 px below centre (y down): the window moves up by 20/480.
  expectPlane(fromOpenCV(500, 250, 319.5, 259.5, 640, 480), 1.28, 1.92, 0.0, 20.0 / 480);
  EXPECT_THROW(fromOpenCV(0, 500, 1, 1, 10, 10), Error);
}

TEST(Conventions, OpenCVCameraProjectsLikeOpenCV) {
  const double fx = 612.5, fy = 580.0, cx = 301.25, cy = 255.75;
  CameraParams p;
  p.width = 640;
  p.height = 480;
  p.eye = {0.5, -1.0, 2.0};
  p.dir = glm::dvec3(0.2, 0.1, -1.0);
  applyImagePlane(fromOpenCV(fx, fy, cx, cy, 640, 480, 0.7), p);
  const auto cam = makeCameraModel(p);
  const CameraFrame f = cam->frame();
  for (const glm::dvec3 cvPoint : {glm::dvec3(0.3, -0.2, 4.0), glm::dvec3(-1.0, 0.7, 2.5)}) {
    // OpenCV camera: x right (U), y down (−V), z forward (−W).
    const glm::dvec3 world = f.e + cvPoint.x * f.u - cvPoint.y * f.v - cvPoint.z * f.w;
    const auto r = cam->project(world);
    ASSERT_TRUE(r);
    EXPECT_NEAR(r->x, fx * cvPoint.x / cvPoint.z + cx + 0.5, 1e-9);
    EXPECT_NEAR(r->y, fy * cvPoint.y / cvPoint.z + cy + 0.5, 1e-9);
  }
  // And back: the summary recovers the intrinsics.
  const ConventionSummary s =
      toConventions({cam->d(), cam->vw(), cam->vh(), cam->shift()}, 640, 480);
  EXPECT_NEAR(s.fx, fx, 1e-9);
  EXPECT_NEAR(s.fy, fy, 1e-9);
  EXPECT_NEAR(s.cx, cx, 1e-9);
  EXPECT_NEAR(s.cy, cy, 1e-9);
}

TEST(Conventions, SummaryOfA35mmLens) {
  // 50 mm on a 36 x 24 sensor at 3:2: horizontal fov 2·atan(18/50), 35 mm equivalent 50.
  const ConventionSummary s = toConventions({1.0, 0.72, 0.48, {0, 0}}, 300, 200);
  EXPECT_NEAR(s.fovXDeg, 2 * std::atan(18.0 / 50) * 180 / M_PI, 1e-9);
  EXPECT_NEAR(s.fovYDeg, 2 * std::atan(12.0 / 50) * 180 / M_PI, 1e-9);
  EXPECT_NEAR(s.focal35DiagonalMm, 50.0, 1e-9);
  EXPECT_NEAR(s.focal35HorizontalMm, 50.0, 1e-9);
  EXPECT_NEAR(s.pbrtFovDeg, s.fovYDeg, 1e-12);
}

}  // namespace
}  // namespace aperture
