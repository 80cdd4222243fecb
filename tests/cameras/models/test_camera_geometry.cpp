// Camera geometry in closed form: perspective fov and edges, parallel projections, shift,
// architectural mode, thin lens, panoramas, packets against the scalar path, view volumes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <tuple>

#include "cameras/geometry/view_volume.h"
#include "cameras/models/base.h"
#include "cameras/models/perspective.h"
#include "cameras/registry/registry.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "tests/camera_support.h"

namespace aperture {
namespace {

using test::angleBetween;
using test::PacketBuffer;

double rad(double deg) { return deg * kPi / 180.0; }

std::unique_ptr<CameraBase> make(const CameraParams& p,
                                 const glm::dvec3& renderOrigin = glm::dvec3(0.0)) {
  return makeCameraModel(p, renderOrigin);
}

glm::dvec3 toDouble(const glm::vec3& v) { return glm::dvec3(v); }

/// Generates the single-pixel packet (1x1) for pixel (i, j), sample s.
struct Lane {
  glm::vec3 org, dir;
  int valid;
};
Lane pixelLane(const Camera& cam, int i, int j, int s = 0) {
  PacketBuffer buf(1);
  PacketRequest req;
  req.x0 = j;
  req.y0 = i;
  req.blockW = req.blockH = 1;
  req.sample = s;
  int valid = 7;
  cam.generate(req, buf.lanes(), &valid);
  const RayLanes& l = buf.lanes();
  return {{l.orgX[0], l.orgY[0], l.orgZ[0]}, {l.dirX[0], l.dirY[0], l.dirZ[0]}, valid};
}

// ---------------------------------------------------------------------------------------
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

// ---------------------------------------------------------------------------------------
// Orthographic and oblique.

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

// ---------------------------------------------------------------------------------------
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

// ---------------------------------------------------------------------------------------
// Thin lens.

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

// ---------------------------------------------------------------------------------------
// Panoramas.

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
