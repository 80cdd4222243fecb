// Blender's camera: the sensor fit and the lens shift against Blender's view-plane formula
// (BKE_camera_params_compute_viewplane), written out below independently of cameras/, and the
// clip planes (planar depths) through the frame loop.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/conventions.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/camera_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

// ---- Blender's formula, as its source states it ------------------------------------------

enum class Fit { Auto, Horizontal, Vertical };

struct BlenderCam {
  double lens = 50, sensorX = 36, sensorY = 24;
  Fit fit = Fit::Auto;
  double shiftX = 0, shiftY = 0;
};

/// Continuous raster position (column from the left edge, row from the top edge, pixels) of a
/// point at (X right, Y up, Z > 0 forward) in Blender's camera, for a winx x winy image with
/// square pixels. BKE_camera_sensor_size: the sensor height for VERTICAL, else the width.
/// BKE_camera_sensor_fit: AUTO is HORIZONTAL when winx >= winy, else VERTICAL. Then
/// viewfac = winx (HORIZONTAL) or winy (VERTICAL), pixsize = sensor·clip_start / lens / viewfac,
/// the view plane at depth clip_start is [−winx/2 + dx, winx/2 + dx] x [−winy/2 + dy,
/// winy/2 + dy] times pixsize with (dx, dy) = shift·viewfac.
glm::dvec2 blenderRaster(const BlenderCam& c, int winx, int winy, const glm::dvec3& p) {
  const double clipStart = 0.1;
  const double sensor = c.fit == Fit::Vertical ? c.sensorY : c.sensorX;
  Fit fit = c.fit;
  if (fit == Fit::Auto) fit = winx >= winy ? Fit::Horizontal : Fit::Vertical;
  const double viewfac = fit == Fit::Horizontal ? winx : winy;
  const double pixsize = sensor * clipStart / c.lens / viewfac;
  const double dx = c.shiftX * viewfac, dy = c.shiftY * viewfac;
  const double xmin = (-0.5 * winx + dx) * pixsize, ymax = (0.5 * winy + dy) * pixsize;
  // The point's image on the plane at depth clip_start.
  const double px = p.x * clipStart / p.z, py = p.y * clipStart / p.z;
  return {(px - xmin) / pixsize, (ymax - py) / pixsize};
}

// ---- aperture's camera for the same parameters --------------------------------------------

SensorFit ours(Fit f) {
  return f == Fit::Auto         ? SensorFit::Auto
         : f == Fit::Horizontal ? SensorFit::Horizontal
                                : SensorFit::Vertical;
}

/// Blender's camera at the origin looking down −z with +y up (its own pose), so camera space
/// (X, Y, Z forward) is world (X, Y, −Z).
CameraParams apertureParams(const BlenderCam& c, int width, int height) {
  CameraParams p;
  p.width = width;
  p.height = height;
  p.eye = glm::dvec3(0.0);
  p.dir = glm::dvec3(0, 0, -1);
  p.up = glm::dvec3(0, 1, 0);
  p.focalLengthMm = c.lens;
  p.sensorMm = {c.sensorX, c.sensorY};
  p.sensorFit = ours(c.fit);
  if (c.shiftX != 0 || c.shiftY != 0) p.blenderShift = glm::dvec2(c.shiftX, c.shiftY);
  return p;
}

glm::dvec2 apertureRaster(const CameraParams& params, const glm::dvec3& p) {
  const auto cam = makeCameraModel(params);
  const std::optional<glm::dvec2> r = cam->project({p.x, p.y, -p.z});
  EXPECT_TRUE(r.has_value());
  return r.value_or(glm::dvec2(std::numeric_limits<double>::quiet_NaN()));
}

/// Points spread over (and beyond) the field of a 50 mm lens, at several depths.
const std::vector<glm::dvec3> kPoints = {
    {0.0, 0.0, 3.0}, {0.9, 0.2, 2.5}, {-1.3, 0.7, 4.0}, {0.4, -1.1, 2.0}, {2.0, 1.5, 5.5}};

struct ImageShape {
  const char* name;
  int width, height;
};
const ImageShape kBlenderShapes[] = {{"landscape 16:9", 1920, 1080}, {"landscape 4:3", 640, 480},
                                     {"portrait 3:4", 480, 640},     {"portrait 9:16", 1080, 1920},
                                     {"square", 512, 512},           {"odd", 61, 45}};
const Fit kFits[] = {Fit::Auto, Fit::Horizontal, Fit::Vertical};
const char* fitName(Fit f) {
  return f == Fit::Auto ? "AUTO" : f == Fit::Horizontal ? "HORIZONTAL" : "VERTICAL";
}

/// The largest raster distance between Blender's and aperture's image of kPoints.
double worstPixelError(const BlenderCam& c, const CameraParams& params, int w, int h) {
  double worst = 0;
  for (const glm::dvec3& p : kPoints)
    worst = std::max(worst, glm::length(apertureRaster(params, p) - blenderRaster(c, w, h, p)));
  return worst;
}

TEST(BlenderCamera, SensorFitMatchesBlenderForEveryShapeAndFit) {
  for (const glm::dvec2 sensor : {glm::dvec2(36, 24), glm::dvec2(24, 36), glm::dvec2(23.5, 15.6)})
    for (const ImageShape& s : kBlenderShapes)
      for (Fit fit : kFits) {
        SCOPED_TRACE(testing::Message()
                     << s.name << " " << fitName(fit) << " sensor " << sensor.x << "x" << sensor.y);
        BlenderCam c;
        c.lens = 35;
        c.sensorX = sensor.x;
        c.sensorY = sensor.y;
        c.fit = fit;
        EXPECT_LT(worstPixelError(c, apertureParams(c, s.width, s.height), s.width, s.height),
                  1e-9);
      }
}

TEST(BlenderCamera, LensShiftMatchesBlenderForEveryShapeAndFit) {
  for (const ImageShape& s : kBlenderShapes)
    for (Fit fit : kFits) {
      SCOPED_TRACE(testing::Message() << s.name << " " << fitName(fit));
      BlenderCam c;
      c.fit = fit;
      c.shiftX = 0.17;
      c.shiftY = -0.31;
      EXPECT_LT(worstPixelError(c, apertureParams(c, s.width, s.height), s.width, s.height), 1e-9);
      // Blender's units are not viewports: reading the same numbers as `shift` is off
      // wherever the fit does not span the side (and always on the other axis).
      CameraParams asViewports = apertureParams(c, s.width, s.height);
      asViewports.blenderShift.reset();
      asViewports.shift = {c.shiftX, c.shiftY};
      if (s.width != s.height) {
        EXPECT_GT(worstPixelError(c, asViewports, s.width, s.height), 1.0);
      }
    }
}

// Where Blender's centre shift puts the principal point, in pixels: shift_x = 0.25 on a
// 1920 x 1080 image moves the view plane by 0.25·1920 = 480 px, so the view axis is seen
// 480 px left of the centre; on 1080 x 1920 (AUTO fits the height) shift_y = 0.1 moves it by
// 0.1·1920 = 192 px, the axis 192 px below the centre.
TEST(BlenderCamera, LensShiftMovesThePrincipalPointByFractionsOfTheFittedSide) {
  BlenderCam c;
  c.shiftX = 0.25;
  glm::dvec2 axis = apertureRaster(apertureParams(c, 1920, 1080), {0, 0, 7});
  EXPECT_NEAR(axis.x, 960.0 - 480.0, 1e-9);
  EXPECT_NEAR(axis.y, 540.0, 1e-9);
  c.shiftX = 0;
  c.shiftY = 0.1;
  axis = apertureRaster(apertureParams(c, 1080, 1920), {0, 0, 7});
  EXPECT_NEAR(axis.x, 540.0, 1e-9);
  EXPECT_NEAR(axis.y, 960.0 + 192.0, 1e-9);
}

// The formula aperture used before issue 11: the image as the largest centred window of its
// aspect inside the sensor. Kept here only to show the test above would have caught it.
glm::dvec2 oldCropViewport(double lens, glm::dvec2 sensor, int width, int height) {
  const double aspect = double(width) / height;
  double cropW = sensor.x, cropH = sensor.y;
  if (cropW / cropH > aspect)
    cropW = cropH * aspect;
  else
    cropH = cropW / aspect;
  return {cropW / lens, cropH / lens};
}

TEST(BlenderCamera, TheOldCropFormulaFailsFor4To3AndPortraitImages) {
  BlenderCam c;  // 50 mm, 36 x 24 mm, AUTO: Blender's defaults
  auto oldParams = [&](int w, int h) {
    CameraParams p = apertureParams(c, w, h);
    p.focalLengthMm.reset();
    p.d = 1.0;
    p.viewport = oldCropViewport(c.lens, {c.sensorX, c.sensorY}, w, h);
    return p;
  };
  // A point on Blender's right image edge, halfway up: 640 x 480 (AUTO: the 36 mm width spans
  // 640 px) and 480 x 640 (the 36 mm width spans the 640 px height).
  const glm::dvec3 edge(3.6, 0.0, 10.0);  // x/z = (36/50)/2: half the fitted sensor over f
  EXPECT_NEAR(blenderRaster(c, 640, 480, edge).x, 640.0, 1e-9);
  EXPECT_NEAR(apertureRaster(apertureParams(c, 640, 480), edge).x, 640.0, 1e-9);
  // Old: vw = 24·(4/3)/50 = 0.64, so the point lands at (0.36/0.64 + ½)·640 = 680: 40 px off.
  EXPECT_NEAR(apertureRaster(oldParams(640, 480), edge).x, 680.0, 1e-9);
  EXPECT_GT(worstPixelError(c, oldParams(640, 480), 640, 480), 1.0);
  EXPECT_GT(worstPixelError(c, oldParams(480, 640), 480, 640), 1.0);
  EXPECT_GT(worstPixelError(c, oldParams(512, 512), 512, 512), 1.0);
  // Images at least as wide as the sensor (3:2 here) were right, which is why the golden
  // images (93 x 61) keep their hashes.
  EXPECT_LT(worstPixelError(c, oldParams(1920, 1080), 1920, 1080), 1e-9);
  EXPECT_LT(worstPixelError(c, oldParams(93, 61), 93, 61), 1e-9);
}

// fromBlender and the camera share viewportOfSensor and shiftOfBlenderShift: one formula.
TEST(BlenderCamera, FromBlenderEqualsTheCameraBuiltFromTheSameParameters) {
  for (const ImageShape& s : kBlenderShapes)
    for (Fit fit : kFits) {
      const ImagePlane plane =
          fromBlender(35, 36, 24, ours(fit), s.width, s.height, 1.0, {0.1, 0.2});
      BlenderCam c;
      c.lens = 35;
      c.fit = fit;
      c.shiftX = 0.1;
      c.shiftY = 0.2;
      const auto cam = makeCameraModel(apertureParams(c, s.width, s.height));
      EXPECT_DOUBLE_EQ(plane.vw, cam->vw());
      EXPECT_DOUBLE_EQ(plane.vh, cam->vh());
      EXPECT_DOUBLE_EQ(plane.shift.x, cam->shift().x);
      EXPECT_DOUBLE_EQ(plane.shift.y, cam->shift().y);
    }
}

TEST(BlenderCamera, FlagsAndConflicts) {
  const CameraParams p = test::cameraParamsFromFlags(
      "--dir 0,0,-1 --focal-length 50 --sensor-fit vertical --blender-shift 0.1,0.2 "
      "--clip 0.5,20");
  EXPECT_EQ(p.sensorFit, SensorFit::Vertical);
  ASSERT_TRUE(p.blenderShift && p.clip);
  EXPECT_EQ(*p.blenderShift, glm::dvec2(0.1, 0.2));
  EXPECT_EQ(*p.clip, glm::dvec2(0.5, 20));
  EXPECT_THROW(test::cameraParamsFromFlags("--dir 0,0,-1 --blender-shift 0.1,0 --shift 0.1,0"),
               Error);
  EXPECT_THROW(test::cameraParamsFromFlags("--dir 0,0,-1 --sensor-fit vertical"),
               Error);  // needs a lens
  EXPECT_THROW(test::cameraParamsFromFlags("--dir 0,0,-1 --focal-length 50 --sensor-fit fill"),
               Error);
  EXPECT_THROW(test::cameraParamsFromFlags("--dir 0,0,-1 --clip 1,-5"), Error);
  CameraParams bad = p;
  bad.clip = glm::dvec2(5, 5);
  EXPECT_THROW(makeCamera(bad), Error);  // near must be below far
  bad = p;
  bad.shift = {0.1, 0};
  EXPECT_THROW(makeCamera(bad), Error);  // shift and Blender shift together
  bad = CameraParams{};
  bad.type = "orthographic";
  bad.viewport = glm::dvec2(2, 2);
  bad.clip = glm::dvec2(1, 2);
  EXPECT_THROW(makeCamera(bad), Error);  // clip is for perspective and thin lens only
}

// ---- Clip planes ---------------------------------------------------------------------------

// A quad at z = 0 seen from (0, 0, 10) down −z: every pixel sees it at depth 10 exactly, and
// with a 100° field the corner rays travel up to 10 / cos ≈ 17.5 to reach it. So a clip
// that measured distance instead of depth would lose the corners for far = 10.5 and keep them
// for near = 10.5.
struct ClipScene {
  Mesh quad = loadMesh("procedural:quad?size=200&z=0");
  Device device;
  Scene scene{device, {&quad}};
};

CameraParams clipCamera(const std::string& type, glm::dvec2 clip, int spp) {
  CameraParams p;
  p.type = type;
  p.width = 40;
  p.height = 30;
  p.spp = spp;
  p.eye = {0, 0, 10};
  p.at = glm::dvec3(0.0);
  p.fovDeg = 100;
  p.fovAxis = FovAxis::X;
  p.clip = clip;
  if (type == "thinlens") {
    p.apertureRadius = 0.5;
    p.focusDistance = 6.0;
  }
  return p;
}

/// Renders depth and colour; returns the number of pixels fully covered (alpha 1) and checks
/// every covered pixel's depth is 10.
int coveredPixels(const ClipScene& s, const CameraParams& p) {
  const auto cam = makeCamera(p, s.scene.renderOrigin());
  Framebuffer fb(p.width, p.height, kAovColor | kAovDepth);
  RenderSettings settings;
  settings.spp = p.spp;
  renderImage(s.scene, *cam, settings, fb);
  int covered = 0;
  for (size_t k = 0; k < fb.pixelCount(); ++k) {
    if (fb.rgba[4 * k + 3] == 1.0f) {
      ++covered;
      EXPECT_NEAR(fb.depth[k], 10.0f, 1e-4f) << "pixel " << k;
    }
  }
  return covered;
}

TEST(BlenderCamera, ClipKeepsExactlyTheDepthsBetweenNearAndFar) {
  const ClipScene s;
  for (const char* type : {"perspective", "thinlens"})
    for (int spp : {1, 4}) {
      SCOPED_TRACE(testing::Message() << type << " spp " << spp);
      const int all = 40 * 30;
      EXPECT_EQ(coveredPixels(s, clipCamera(type, {9.5, 10.5}, spp)), all);  // between
      EXPECT_EQ(coveredPixels(s, clipCamera(type, {0.1, 9.9}, spp)), 0);     // beyond far
      EXPECT_EQ(coveredPixels(s, clipCamera(type, {10.5, 100}, spp)), 0);    // before near
    }
}

TEST(BlenderCamera, ClippedRaysCarryNearAndFarOverTheirCosine) {
  for (const char* type : {"perspective", "thinlens"}) {
    SCOPED_TRACE(type);
    const CameraParams p = clipCamera(type, {2.0, 30.0}, 4);
    const auto cam = makeCamera(p);
    const glm::dvec3 axis(0, 0, -1);
    for (int width : {1, 4, 8, 16}) {
      test::PacketBuffer buf(width);
      const int bw = width == 1 ? 1 : 4, bh = width / bw;
      alignas(64) int valid[16];
      for (int sample : {0, 3, PacketRequest::kCentreRay}) {
        const PacketRequest req{36, 26, bw, bh, sample};  // the bottom-right corner
        cam->generate(req, buf.lanes(), valid);
        const RayLanes& l = buf.lanes();
        for (int k = 0; k < width; ++k) {
          const double c = glm::dot(glm::dvec3(l.dirX[k], l.dirY[k], l.dirZ[k]), axis);
          EXPECT_NEAR(l.tnear[k] * c, 2.0, 1e-5);
          EXPECT_NEAR(l.tfar[k] * c, 30.0, 1e-4);
          EXPECT_LT(c, 0.8);  // corner rays: depth and distance differ
        }
      }
    }
    // Without a clip the contract's defaults.
    CameraParams open = p;
    open.clip.reset();
    test::PacketBuffer buf(16);
    alignas(64) int valid[16];
    makeCamera(open)->generate({0, 0, 4, 4, 0}, buf.lanes(), valid);
    for (int k = 0; k < 16; ++k) {
      EXPECT_EQ(buf.lanes().tnear[k], 0.0f);
      EXPECT_EQ(buf.lanes().tfar[k], std::numeric_limits<float>::infinity());
    }
  }
}

}  // namespace
}  // namespace aperture
