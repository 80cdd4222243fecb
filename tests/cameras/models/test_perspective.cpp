// The perspective camera in closed form: the field of view over a sweep of fovs, aspects and
// axes, corner rays, look-at against a view direction, degenerate inputs, focal length and
// sensor fit; shift (its rays the crop of a larger viewport) and the architectural mode. And,
// through the frame loop, a shifted camera renders the crop of a larger unshifted one, pixel for
// pixel on Z and primID.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/models/perspective.h"
#include "cameras/registry/registry.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/camera_support.h"

namespace aperture {
namespace {

using test::angleBetween;
using test::Lane;
using test::make;
using test::pixelLane;
using test::rad;
using test::toDouble;

// Perspective: fov sweep x aspect x fov axis.

struct FovCase {
  double fovDeg;
  int width, height;
  FovAxis axis;
};

class PerspectiveFov : public ::testing::TestWithParam<FovCase> {};

TEST_P(PerspectiveFov, CentreRayIsMinusWAndEdgeRaysMakeHalfFov) {
  const FovCase c = GetParam();
  CameraParams p = test::tiltedParams("perspective");
  p.width = c.width;
  p.height = c.height;
  p.fovDeg = c.fovDeg;
  p.fovAxis = c.axis;
  const auto cam = make(p);
  const glm::dvec3 axis = -cam->frame().w;
  const double aspect = double(c.width) / c.height;
  const double t = std::tan(rad(c.fovDeg) / 2);
  double halfX = 0, halfY = 0;  // expected half-angles across the image edges
  switch (c.axis) {
    case FovAxis::X:
      halfX = rad(c.fovDeg) / 2;
      halfY = std::atan(t / aspect);
      break;
    case FovAxis::Y:
      halfY = rad(c.fovDeg) / 2;
      halfX = std::atan(t * aspect);
      break;
    case FovAxis::Diagonal: {
      const double diag = std::hypot(double(c.width), double(c.height));
      halfX = std::atan(t * c.width / diag);
      halfY = std::atan(t * c.height / diag);
      break;
    }
  }
  glm::dvec3 org, dir;
  // The centre of the image (a pixel centre when the size is odd) looks exactly along −W.
  cam->ray(0.5 * c.width, 0.5 * c.height, 0.5, 0.5, org, dir);
  EXPECT_EQ(glm::vec3(dir), glm::vec3(axis));
  if (c.width % 2 == 1 && c.height % 2 == 1) {
    const Lane centre = pixelLane(*cam, c.height / 2, c.width / 2);
    EXPECT_EQ(centre.dir, glm::vec3(axis)) << "odd image: the centre pixel's ray is −W";
  }
  // Middle of the left and right edges, top and bottom edges: fov_x / 2 and fov_y / 2.
  const double rx[4][2] = {{0.0, 0.5 * c.height},
                           {double(c.width), 0.5 * c.height},
                           {0.5 * c.width, 0.0},
                           {0.5 * c.width, double(c.height)}};
  for (int e = 0; e < 4; ++e) {
    cam->ray(rx[e][0], rx[e][1], 0.5, 0.5, org, dir);
    const double expected = e < 2 ? halfX : halfY;
    EXPECT_NEAR(angleBetween(dir, axis), expected, 1e-6) << "edge " << e;
    EXPECT_NEAR(angleBetween(toDouble(glm::vec3(dir)), axis), expected, 1e-6) << "edge " << e;
  }
  // Corner: the diagonal half-angle.
  cam->ray(0.0, 0.0, 0.5, 0.5, org, dir);
  EXPECT_NEAR(angleBetween(dir, axis), std::atan(std::hypot(std::tan(halfX), std::tan(halfY))),
              1e-6);
  EXPECT_NEAR(glm::length(dir), 1.0, 1e-15);
}

std::vector<FovCase> fovCases() {
  std::vector<FovCase> cases;
  const int sizes[][2] = {{33, 33}, {160, 90}, {161, 91}, {32, 128}, {33, 131}};
  for (double fov : {0.01, 1.0, 40.0, 90.0, 170.0})
    for (const auto& s : sizes)
      for (FovAxis a : {FovAxis::X, FovAxis::Y, FovAxis::Diagonal})
        cases.push_back({fov, s[0], s[1], a});
  return cases;
}

std::string fovName(const ::testing::TestParamInfo<FovCase>& info) {
  const FovCase& c = info.param;
  const char* axis = c.axis == FovAxis::X ? "x" : c.axis == FovAxis::Y ? "y" : "diag";
  std::string fov = std::to_string(c.fovDeg);
  for (char& ch : fov)
    if (ch == '.') ch = 'p';
  return "fov" + fov + "_" + std::to_string(c.width) + "x" + std::to_string(c.height) + "_" + axis;
}

INSTANTIATE_TEST_SUITE_P(Sweep, PerspectiveFov, ::testing::ValuesIn(fovCases()), fovName);

TEST(PerspectiveCamera, FovOutsideOpenRangeIsAnError) {
  for (double fov : {0.0, -1.0, 180.0, 181.0, 1e9, std::nan(""), double(INFINITY)}) {
    CameraParams p;
    p.fovDeg = fov;
    EXPECT_THROW(makeCamera(p), Error) << "fov " << fov;
  }
  CameraParams p;
  p.fovDeg = 179.9;
  EXPECT_NO_THROW(makeCamera(p));
}

TEST(PerspectiveCamera, CornerRaysMatchTheLectureFormula) {
  CameraParams p = test::tiltedParams("perspective");
  p.width = 40;
  p.height = 30;
  p.d = 2.5;
  p.viewport = glm::dvec2(3.0, 1.7);
  const auto cam = make(p);
  const CameraFrame f = CameraFrame::fromLookAt(p.eye, *p.at, p.up);
  for (int i : {0, p.height - 1})
    for (int j : {0, p.width - 1}) {
      const double u = ((j + 0.5) / p.width - 0.5) * 3.0;
      const double v = -((i + 0.5) / p.height - 0.5) * 1.7;
      const glm::dvec3 g = u * f.u + v * f.v - 2.5 * f.w;
      const Lane lane = pixelLane(*cam, i, j);
      EXPECT_EQ(lane.dir, glm::vec3(g / glm::length(g))) << i << "," << j;
      EXPECT_EQ(lane.org, glm::vec3(p.eye));
      EXPECT_EQ(lane.valid, -1);
    }
}

TEST(PerspectiveCamera, LookAtAndViewDirectionGiveIdenticalRays) {
  CameraParams a;
  a.width = 17;
  a.height = 11;
  a.eye = {1.0, 2.0, 3.0};
  a.at = glm::dvec3(-1.0, 2.5, -1.0);
  a.up = {0.0, 0.0, 1.0};
  CameraParams b = a;
  b.at.reset();
  b.dir = glm::dvec3(-2.0, 0.5, -4.0);
  const auto ca = makeCamera(a), cb = makeCamera(b);
  for (int i = 0; i < a.height; ++i)
    for (int j = 0; j < a.width; ++j) {
      const Lane la = pixelLane(*ca, i, j), lb = pixelLane(*cb, i, j);
      ASSERT_EQ(la.dir, lb.dir);
      ASSERT_EQ(la.org, lb.org);
    }
}

TEST(PerspectiveCamera, DegenerateInputsThrow) {
  const double nan = std::nan(""), inf = INFINITY;
  std::vector<std::pair<const char*, CameraParams>> bad;
  auto add = [&](const char* what, auto edit) {
    CameraParams p;
    p.fovDeg = 60;
    edit(p);
    bad.emplace_back(what, p);
  };
  add("up parallel to view", [](CameraParams& p) { p.up = {0, 0, -3}; });
  add("up antiparallel", [](CameraParams& p) { p.up = {0, 0, 1}; });
  add("zero up", [](CameraParams& p) { p.up = {0, 0, 0}; });
  add("zero dir", [](CameraParams& p) { p.dir = glm::dvec3(0.0); });
  add("at == eye", [](CameraParams& p) { p.at = p.eye; });
  add("nan eye", [nan](CameraParams& p) { p.eye.x = nan; });
  add("inf at", [inf](CameraParams& p) { p.at = glm::dvec3(inf, 0, 0); });
  add("nan up", [nan](CameraParams& p) { p.up.y = nan; });
  add("both at and dir", [](CameraParams& p) {
    p.at = glm::dvec3(0.0);
    p.dir = glm::dvec3(0, 0, -1);
  });
  add("d = 0", [](CameraParams& p) { p.d = 0.0; });
  add("d < 0", [](CameraParams& p) { p.d = -1.0; });
  add("d nan", [nan](CameraParams& p) { p.d = nan; });
  add("viewport 0", [](CameraParams& p) { p.viewport = glm::dvec2(0.0, 1.0); });
  add("viewport < 0", [](CameraParams& p) { p.viewport = glm::dvec2(1.0, -1.0); });
  add("viewport inf", [inf](CameraParams& p) { p.viewport = glm::dvec2(inf, 1.0); });
  add("focal 0", [](CameraParams& p) { p.focalLengthMm = 0.0; });
  add("spp 0", [](CameraParams& p) { p.spp = 0; });
  add("width 0", [](CameraParams& p) { p.width = 0; });
  add("nan shift", [nan](CameraParams& p) { p.shift.x = nan; });
  add("unknown type", [](CameraParams& p) { p.type = "pinhole3000"; });
  add("aperture on perspective", [](CameraParams& p) { p.apertureRadius = 0.1; });
  add("architectural straight up", [](CameraParams& p) {
    p.architectural = true;
    p.dir = glm::dvec3(0.0, 1.0, -0.001);
  });
  for (const auto& [what, p] : bad) EXPECT_THROW(makeCamera(p), Error) << what;
}

TEST(PerspectiveCamera, FocalLengthAndSensorFitLikeBlendersAuto) {
  CameraParams p;
  p.width = 300;
  p.height = 200;
  p.focalLengthMm = 50;
  auto cam = make(p);
  EXPECT_DOUBLE_EQ(cam->vw(), 36.0 / 50);
  EXPECT_DOUBLE_EQ(cam->vh(), 24.0 / 50);
  p.width = 200;  // square image: the 36 mm sensor width spans both sides (Blender's AUTO)
  cam = make(p);
  EXPECT_DOUBLE_EQ(cam->vw(), 36.0 / 50);
  EXPECT_DOUBLE_EQ(cam->vh(), 36.0 / 50);
  p.width = 400;  // 2:1: 36 x 18 mm
  cam = make(p);
  EXPECT_DOUBLE_EQ(cam->vw(), 36.0 / 50);
  EXPECT_DOUBLE_EQ(cam->vh(), 18.0 / 50);
}

// Shift and the architectural mode.

TEST(PerspectiveShift, ShiftedRaysEqualTheCropOfALargerViewport) {
  // Powers of two make both pixel mappings exact, so the rays agree bit for bit.
  CameraParams a = test::tiltedParams("perspective");
  a.width = 64;
  a.height = 32;
  a.d = 1.0;
  a.viewport = glm::dvec2(2.0, 1.0);
  a.shift = {0.25, -0.125};
  CameraParams b = a;
  b.width = 128;
  b.height = 64;
  b.viewport = glm::dvec2(4.0, 2.0);
  b.shift = {0.0, 0.0};
  const int dj = 48, di = 20;  // W/2 + sx·W, H/2 − sy·H
  const auto ca = makeCamera(a), cb = makeCamera(b);
  for (int i = 0; i < a.height; ++i)
    for (int j = 0; j < a.width; ++j) {
      const Lane la = pixelLane(*ca, i, j), lb = pixelLane(*cb, i + di, j + dj);
      ASSERT_EQ(la.dir, lb.dir) << i << "," << j;
      ASSERT_EQ(la.org, lb.org);
    }
}

TEST(PerspectiveShift, DescriptionAndNdcIncludeTheShift) {
  CameraParams p = test::tiltedParams("perspective");
  p.width = 50;
  p.height = 40;
  p.fovDeg = 55;
  p.shift = {0.3, -0.2};
  const auto cam = make(p);
  const CameraDescription desc = cam->describe();
  bool found = false;
  for (const auto& [k, v] : desc.extra)
    if (k == "shift") {
      found = true;
      EXPECT_DOUBLE_EQ(std::stod(v), 0.3) << v;
    }
  EXPECT_TRUE(found);
  glm::dvec3 org, dir;
  cam->ray(7.25, 31.5, 0.5, 0.5, org, dir);
  ASSERT_TRUE(desc.ndcFromWorld.has_value());
  const glm::dvec4 ndc = *desc.ndcFromWorld * glm::dvec4(org + 3.0 * dir, 1.0);
  EXPECT_NEAR(ndc.x / ndc.w * p.width, 7.25, 1e-9);
  EXPECT_NEAR(ndc.y / ndc.w * p.height, 31.5, 1e-9);
}

std::vector<double> columnsOfVerticalSegment(bool architectural, double tiltDeg) {
  CameraParams p;
  p.width = 640;
  p.height = 480;
  p.fovDeg = 60;
  p.eye = {0.0, 1.5, 0.0};
  const double yaw = rad(20.0), tilt = rad(tiltDeg);
  p.dir =
      glm::dvec3(std::cos(tilt) * std::sin(yaw), std::sin(tilt), -std::cos(tilt) * std::cos(yaw));
  p.up = {0.0, 1.0, 0.0};
  p.architectural = architectural;
  const auto cam = make(p);
  std::vector<double> columns;
  for (double y = 0.0; y <= 12.0; y += 1.5) {
    const auto r = cam->project({3.0, y, -8.0});
    if (r) columns.push_back(r->x);
  }
  return columns;
}

TEST(PerspectiveArchitectural, VerticalSegmentProjectsToOneColumn) {
  const auto cols = columnsOfVerticalSegment(true, 30.0);
  ASSERT_GE(cols.size(), 5u);
  for (double c : cols) EXPECT_NEAR(c, cols[0], 1e-3);
  const auto tilted = columnsOfVerticalSegment(false, 30.0);
  ASSERT_GE(tilted.size(), 5u);
  const auto [lo, hi] = std::minmax_element(tilted.begin(), tilted.end());
  EXPECT_GT(*hi - *lo, 1.0) << "without the flag, verticals converge";
}

TEST(PerspectiveArchitectural, RequestedAxisStaysAtTheImageCentre) {
  for (double tiltDeg : {-40.0, -5.0, 0.0, 30.0, 75.0}) {
    CameraParams p;
    p.width = 300;
    p.height = 200;
    p.fovDeg = 50;
    p.eye = {2.0, 1.0, 4.0};
    const glm::dvec3 dir(std::cos(rad(tiltDeg)) * 0.6, std::sin(rad(tiltDeg)),
                         -std::cos(rad(tiltDeg)) * 0.8);
    p.dir = dir;
    p.architectural = true;
    const auto cam = make(p);
    const auto r = cam->project(p.eye + 5.0 * dir);
    ASSERT_TRUE(r);
    EXPECT_NEAR(r->x, 150.0, 1e-9);
    EXPECT_NEAR(r->y, 100.0, 1e-9);
    // The image plane is vertical: V is up.
    EXPECT_NEAR(glm::dot(cam->frame().v, glm::dvec3(0, 1, 0)), 1.0, 1e-12);
    // Centre shift = d·tan(tilt) / vh.
    EXPECT_NEAR(cam->shift().y, cam->d() * std::tan(rad(tiltDeg)) / cam->vh(), 1e-12);
  }
}

TEST(PerspectiveShift, ImageEqualsTheCropOfALargerViewportOnZAndPrimId) {
  const Mesh city = loadMesh("procedural:city");
  Device device;
  Scene scene(device, {&city});
  // Powers of two keep both pixel mappings exact, so the rays are bit-identical.
  CameraParams a;
  a.eye = {1.0, 7.0, 19.0};
  a.at = glm::dvec3(0.0, 1.5, 0.0);
  a.width = 128;
  a.height = 64;
  a.d = 1.0;
  a.viewport = glm::dvec2(2.0, 1.0);
  a.shift = {0.25, -0.125};
  CameraParams b = a;
  b.width = 256;
  b.height = 128;
  b.viewport = glm::dvec2(4.0, 2.0);
  b.shift = {0.0, 0.0};
  const int dj = 96, di = 40;  // W·(½ + sx), H·(½ − sy)
  const auto camA = makeCamera(a, scene.renderOrigin());
  const auto camB = makeCamera(b, scene.renderOrigin());
  for (int width : {16, 4}) {
    RenderSettings settings;
    settings.packetWidth = width;
    Framebuffer fa(a.width, a.height, kAovDepth | kAovPrimId);
    Framebuffer fb(b.width, b.height, kAovDepth | kAovPrimId);
    renderImage(scene, *camA, settings, fa);
    settings.packetWidth = 16;
    renderImage(scene, *camB, settings, fb);
    size_t hits = 0;
    for (int i = 0; i < a.height; ++i)
      for (int j = 0; j < a.width; ++j) {
        const size_t ka = size_t(i) * a.width + j, kb = size_t(i + di) * b.width + (j + dj);
        ASSERT_EQ(fa.primId[ka], fb.primId[kb]) << "pixel " << i << "," << j;
        ASSERT_EQ(fa.depth[ka], fb.depth[kb]) << "pixel " << i << "," << j;
        hits += fa.primId[ka] != kInvalidId;
      }
    EXPECT_GT(hits, fa.pixelCount() / 4) << "the shifted window must see the city";
  }
}

}  // namespace
}  // namespace aperture
