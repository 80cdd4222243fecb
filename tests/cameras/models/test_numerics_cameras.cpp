// Numerics of the cameras at their extremes: fields of view, near-degenerate frames, scaled image
// planes, tiny lenses, oblique and orthographic extremes. Part of the numerics tests (issue 5):
// each test checks a closed form or an independent path; the world-space float32 mode's errors are
// measured and printed (docs/numerics.md records them), not asserted.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/exr/exr.h"
#include "core/mesh/mesh.h"
#include "core/queries/trace.h"
#include "core/util/error.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using namespace aperture::test;

// --- Field of view ---------------------------------------------------------------------

std::vector<glm::vec3> rowDirections(const Camera& cam, int width, int row) {
  std::vector<glm::vec3> dirs;
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[16];
  RayLanes lanes;
  lanes.width = 16;
  lanes.orgX = packet.ray.org_x, lanes.orgY = packet.ray.org_y, lanes.orgZ = packet.ray.org_z;
  lanes.tnear = packet.ray.tnear, lanes.dirX = packet.ray.dir_x, lanes.dirY = packet.ray.dir_y;
  lanes.dirZ = packet.ray.dir_z, lanes.time = packet.ray.time, lanes.tfar = packet.ray.tfar;
  lanes.mask = packet.ray.mask, lanes.id = packet.ray.id, lanes.flags = packet.ray.flags;
  for (int x0 = 0; x0 < width; x0 += 16) {
    const PacketRequest req{x0, row, 16, 1, 0};
    cam.generate(req, lanes, valid);
    for (int k = 0; k < 16 && req.pixel(k).column < width; ++k)
      dirs.emplace_back(lanes.dirX[k], lanes.dirY[k], lanes.dirZ[k]);
  }
  return dirs;
}

// At 0.001° over 4096 columns, neighbouring directions differ by 4.3e-9 rad. With the camera
// looking down −z and U = +x, each column's direction is (x, ~0, −1) with |x| <= 8.7e-6, where
// float resolves ~1e-12: every column gets its own float direction, strictly increasing in x.
// A rotated frame cannot do this: a component near 0.5 has a float spacing of 6e-8, ten times
// the 4.3e-9 step, so neighbouring columns round to the same float direction. What the renderer
// guarantees instead is that each direction is computed in double and rounded once (each
// component within half an ulp of the exact unit direction) and monotone (rounding preserves
// order); distinct directions need an axis-aligned frame or a wider field.
TEST(NumericsFov, TinyFovGivesDistinctMonotoneDirectionsOnAnAxisAlignedCamera) {
  CameraParams p;
  p.eye = glm::dvec3(0.0);
  p.dir = glm::dvec3(0, 0, -1);
  p.width = 4096;
  p.height = 1;
  p.fovDeg = 0.001;
  p.fovAxis = FovAxis::X;
  const auto cam = makeCameraModel(p);
  const std::vector<glm::vec3> dirs = rowDirections(*cam, p.width, 0);
  ASSERT_EQ(dirs.size(), 4096u);
  for (size_t j = 0; j < dirs.size(); ++j) {
    ASSERT_TRUE(std::isfinite(dirs[j].x) && std::isfinite(dirs[j].y) && std::isfinite(dirs[j].z));
    if (j > 0) {
      ASSERT_GT(dirs[j].x, dirs[j - 1].x) << "column " << j;
    }
  }
  // The edges of the image at ±0.0005°.
  glm::dvec3 org, dir;
  cam->ray(0.0, 0.5, 0.5, 0.5, org, dir);
  EXPECT_NEAR(std::atan2(-dir.x, -dir.z) / kDeg, 0.0005, 1e-12);
  cam->ray(4096.0, 0.5, 0.5, 0.5, org, dir);
  EXPECT_NEAR(std::atan2(dir.x, -dir.z) / kDeg, 0.0005, 1e-12);

  // Rotated: still monotone along U (the per-component rounding keeps the order).
  p.dir = glm::dvec3(1, -0.7, -0.4);
  const auto rotated = makeCameraModel(p);
  const std::vector<glm::vec3> rdirs = rowDirections(*rotated, p.width, 0);
  const glm::dvec3 u = rotated->frame().u;
  size_t distinct = 1;
  for (size_t j = 1; j < rdirs.size(); ++j) {
    distinct += rdirs[j] != rdirs[j - 1];
    EXPECT_GE(glm::dot(glm::dvec3(rdirs[j]), u) - glm::dot(glm::dvec3(rdirs[j - 1]), u), -1e-7);
  }
  std::printf("[ info ] fov 0.001 deg, rotated frame: %zu distinct float directions of 4096\n",
              distinct);
}

TEST(NumericsFov, WideFovHasFiniteRaysAndExactEdgeAngles180AndAboveAreErrors) {
  CameraParams p;
  p.eye = glm::dvec3(0.0);
  p.dir = glm::dvec3(0, 0, -1);
  p.width = 64;
  p.height = 48;
  p.fovDeg = 179.9;
  p.fovAxis = FovAxis::X;
  const auto cam = makeCameraModel(p);
  for (int i = 0; i < p.height; ++i)
    for (const glm::vec3& d : rowDirections(*cam, p.width, i)) {
      ASSERT_TRUE(std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z));
      EXPECT_NEAR(glm::length(glm::dvec3(d)), 1.0, 1e-6);
    }
  glm::dvec3 org, dir;
  cam->ray(0.0, 24.0, 0.5, 0.5, org, dir);  // left edge, centre row
  EXPECT_NEAR(std::atan2(-dir.x, -dir.z) / kDeg, 89.95, 1e-9);
  cam->ray(64.0, 24.0, 0.5, 0.5, org, dir);
  EXPECT_NEAR(std::atan2(dir.x, -dir.z) / kDeg, 89.95, 1e-9);
  for (double fov : {180.0, 180.0001, 270.0, 360.0, 0.0, -1.0}) {
    p.fovDeg = fov;
    EXPECT_THROW(makeCamera(p), Error) << fov;
  }
}

// --- Up nearly parallel to the view ----------------------------------------------------

TEST(NumericsFrame, UpNearlyParallelGivesAnOrthonormalFrameParallelIsAnError) {
  const glm::dvec3 view = glm::normalize(glm::dvec3(0.3, -0.2, -1.0));
  // A unit vector perpendicular to view, to tilt up away from it.
  const glm::dvec3 side = glm::normalize(glm::cross(view, glm::dvec3(1, 0, 0)));
  for (double deg : {1.0, 0.01, 0.0001, 1e-7}) {
    for (double sign : {1.0, -1.0}) {  // nearly parallel and nearly anti-parallel
      const double a = deg * kDeg;
      const glm::dvec3 up = sign * view * std::cos(a) + side * std::sin(a);
      const CameraFrame f = CameraFrame::fromDirection(glm::dvec3(1e6, 0, 0), view, up);
      const glm::dvec3 axes[3] = {f.u, f.v, f.w};
      for (const glm::dvec3& x : axes) {
        ASSERT_TRUE(std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z)) << deg;
        EXPECT_LE(std::abs(glm::length(x) - 1.0), 1e-12) << deg;
      }
      EXPECT_LE(std::abs(glm::dot(f.u, f.v)), 1e-12) << deg;
      EXPECT_LE(std::abs(glm::dot(f.v, f.w)), 1e-12) << deg;
      EXPECT_LE(std::abs(glm::dot(f.w, f.u)), 1e-12) << deg;
      EXPECT_LE(glm::length(glm::cross(f.u, f.v) - f.w), 1e-12) << deg;  // right-handed
      EXPECT_LE(glm::length(f.w + view), 1e-12) << deg;
      // V leans towards up's part perpendicular to the view (side, times the sign of up).
      EXPECT_GT(glm::dot(f.v, side), 0.999) << deg;
      // The camera built from these parameters renders finite rays.
      CameraParams p;
      p.eye = glm::dvec3(1e6, 0, 0);
      p.dir = view;
      p.up = up;
      p.width = 8;
      p.height = 8;
      const auto cam = makeCameraModel(p);
      glm::dvec3 org, dir;
      cam->ray(0.0, 0.0, 0.5, 0.5, org, dir);
      EXPECT_TRUE(std::isfinite(dir.x + dir.y + dir.z));
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const glm::dvec3 eye(0.0);
  EXPECT_THROW(CameraFrame::fromDirection(eye, view, view), Error);
  EXPECT_THROW(CameraFrame::fromDirection(eye, view, -3.0 * view), Error);
  EXPECT_THROW(CameraFrame::fromDirection(eye, view, glm::dvec3(0.0)), Error);
  EXPECT_THROW(CameraFrame::fromDirection(eye, glm::dvec3(0.0), glm::dvec3(0, 1, 0)), Error);
  EXPECT_THROW(CameraFrame::fromDirection(eye, view, glm::dvec3(0, nan, 0)), Error);
  EXPECT_THROW(CameraFrame::fromDirection(eye, view, glm::dvec3(inf, 1, 0)), Error);
  EXPECT_THROW(CameraFrame::fromDirection(eye, glm::dvec3(nan, 0, -1), glm::dvec3(0, 1, 0)), Error);
  EXPECT_THROW(CameraFrame::fromLookAt(eye, eye, glm::dvec3(0, 1, 0)), Error);
}

// --- Image-plane distance, viewports, aspect ratios ------------------------------------

CameraParams planeCamera(double d, glm::dvec2 viewport, int w, int h) {
  CameraParams p;
  p.eye = glm::dvec3(0.3, 1.2, 9.0);
  p.at = glm::dvec3(0.0, 1.0, 0.0);
  p.width = w;
  p.height = h;
  p.d = d;
  p.viewport = viewport;
  return p;
}

// The same frustum from d = 1e-6 to 1e6 (viewport ∝ d): the directions are the same up to
// rounding of u, v and d, so the images agree (primID, and Z/T to float precision).
TEST(NumericsImagePlane, DistanceScaledWithTheViewportGivesTheSameImage) {
  const Loaded l = load("procedural:city");
  const AovMask aovs = kAovDepth | kAovDistance | kAovPrimId;
  const glm::dvec2 vp(0.8, 0.6);
  const Framebuffer ref = render(*l.scene, planeCamera(1.0, vp, 160, 120), aovs);
  for (double d : {1e-6, 1e-3, 0.37, 1e3, 1e6}) {
    const Agreement g = compare(render(*l.scene, planeCamera(d, d * vp, 160, 120), aovs), ref);
    EXPECT_GE(g.primIdShare, 0.999) << "d = " << d;
    EXPECT_LE(g.maxZ, 1e-6) << "d = " << d;
    EXPECT_LE(g.maxT, 1e-6) << "d = " << d;
  }
}

// A camera looking straight at a large plane at distance D: every hit has planar depth Z = D,
// whatever the viewport (tiny, huge) or aspect ratio (1:1000, 1000:1).
TEST(NumericsImagePlane, TinyHugeViewportsAndExtremeAspectRatiosKeepPlanarDepth) {
  const double D = 7.0;
  const Loaded l = load("procedural:quad?size=2e9&z=0");
  struct Case {
    glm::dvec2 viewport;
    int w, h;
    bool allHit;
  };
  const Case cases[] = {{{1e-6, 1e-6}, 16, 16, true},   {{1e-12, 1e-12}, 8, 8, true},
                        {{1e6, 1e6}, 16, 16, true},     {{1e6, 1e3}, 32, 8, true},
                        {{1.0, 1e-3}, 1000, 1, true},   {{1e-3, 1.0}, 1, 1000, true},
                        {{1000.0, 1.0}, 1000, 1, true}, {{1.0, 1000.0}, 1, 1000, true}};
  for (const Case& c : cases) {
    CameraParams p;
    p.eye = glm::dvec3(0, 0, D);
    p.dir = glm::dvec3(0, 0, -1);
    p.width = c.w;
    p.height = c.h;
    p.d = 1.0;
    p.viewport = c.viewport;
    const Framebuffer fb = render(*l.scene, p, kAovDepth | kAovDistance);
    size_t hits = 0;
    for (size_t i = 0; i < fb.pixelCount(); ++i) {
      if (!std::isfinite(fb.depth[i])) continue;
      ++hits;
      EXPECT_LE(relErr(fb.depth[i], D), 1e-6) << c.viewport.x << "x" << c.viewport.y << " " << i;
      EXPECT_GE(fb.distance[i], float(D) * (1.0f - 1e-6f));
    }
    if (c.allHit) {
      EXPECT_EQ(hits, fb.pixelCount()) << c.viewport.x << "x" << c.viewport.y;
    }
    // Edge angle: the ray through the left edge of the image.
    const auto cam = makeCameraModel(p);
    glm::dvec3 org, dir;
    cam->ray(0.0, 0.5 * c.h, 0.5, 0.5, org, dir);
    EXPECT_NEAR(std::atan2(-dir.x, -dir.z), std::atan(0.5 * c.viewport.x), 1e-12);
  }
}

// --- Thin lens -------------------------------------------------------------------------

TEST(NumericsThinLens, TinyApertureEqualsThePinholeWithinFloatError) {
  const Loaded l = load("procedural:city");
  CameraParams pin = lookAt(glm::dvec3(14, 11, 18), glm::dvec3(0, 1, 0), 128, 96);
  pin.spp = 4;  // as the lens camera's (the geometry AOVs come from the centre rays)
  CameraParams lens = pin;
  lens.type = "thinlens";
  lens.apertureRadius = 1e-9;
  lens.focusDistance = 20.0;
  const auto a = makeCameraModel(pin, l.scene->renderOrigin());
  const auto b = makeCameraModel(lens, l.scene->renderOrigin());
  for (double x : {0.0, 31.3, 64.0, 128.0})
    for (double y : {0.0, 47.9, 96.0})
      for (double lx : {0.0, 0.25, 0.999})
        for (double ly : {0.0, 0.5, 0.999}) {
          glm::dvec3 oa, da, ob, db;
          a->ray(x, y, 0.5, 0.5, oa, da);
          b->ray(x, y, lx, ly, ob, db);
          EXPECT_LE(glm::length(ob - oa), 1.01e-9);
          EXPECT_LE(glm::length(db - da), 1e-9);
          // As rounded to float: the same float direction up to one ulp per component.
          for (int c = 0; c < 3; ++c) EXPECT_LE(std::abs(float(db[c]) - float(da[c])), 6e-8f);
        }
  const Framebuffer fa = render(*l.scene, pin, kAovDepth | kAovDistance | kAovPrimId);
  const Framebuffer fb = render(*l.scene, lens, kAovDepth | kAovDistance | kAovPrimId);
  const Agreement g = compare(fb, fa);
  EXPECT_GE(g.primIdShare, 0.999);
  EXPECT_LE(g.maxZ, 1e-5);
  EXPECT_LE(g.maxT, 1e-5);
}

// Every ray of a pixel passes through the pinhole ray's point at the focus depth f.
TEST(NumericsThinLens, ExtremeFocusDistancesConvergeOnTheFocusPlane) {
  for (double f : {1e-3, 1e6}) {
    CameraParams p;
    p.type = "thinlens";
    p.eye = glm::dvec3(1e3, -2e3, 5e2);
    p.dir = glm::dvec3(-1, 0.3, -0.2);
    p.width = 64;
    p.height = 48;
    p.apertureRadius = 0.05;
    p.focusDistance = f;
    const auto cam = makeCameraModel(p, glm::dvec3(1e3, -2e3, 0));
    const glm::dvec3 axis = -cam->frame().w;
    for (double x : {0.5, 20.2, 63.5})
      for (double y : {0.5, 47.5}) {
        glm::dvec3 o0, d0;
        cam->ray(x, y, 0.5, 0.5, o0, d0);  // the lens centre: the pinhole ray
        const glm::dvec3 focus = o0 + d0 * (f / glm::dot(d0, axis));
        for (double lx : {0.0, 0.3, 0.999})
          for (double ly : {0.01, 0.7}) {
            glm::dvec3 o, d;
            cam->ray(x, y, lx, ly, o, d);
            ASSERT_TRUE(std::isfinite(d.x + d.y + d.z + o.x + o.y + o.z));
            EXPECT_NEAR(glm::length(d), 1.0, 1e-15);
            const double depth0 = glm::dot(o - o0, axis);  // the lens lies in the eye plane
            EXPECT_NEAR(depth0, 0.0, 1e-12);
            const glm::dvec3 at = o + d * ((f - depth0) / glm::dot(d, axis));
            EXPECT_LE(glm::length(at - focus), 1e-9 * std::max(f, 1.0)) << f;
          }
      }
  }
}

// --- Oblique and orthographic extremes -------------------------------------------------

TEST(NumericsParallel, ObliqueUpTo88Point9DegreesHitsAPlaneAtTheClosedForm) {
  const double D = 2.0;
  const Loaded l = load("procedural:quad?size=2000&z=0");
  for (glm::dvec2 angles :
       {glm::dvec2(88.9, 0), glm::dvec2(0, -88.9), glm::dvec2(60, 60), glm::dvec2(-45, 30)}) {
    CameraParams p;
    p.type = "oblique";
    p.eye = glm::dvec3(0, 0, D);
    p.dir = glm::dvec3(0, 0, -1);
    p.width = 16;
    p.height = 12;
    p.viewport = glm::dvec2(1.0, 0.75);
    p.obliqueAnglesDeg = angles;
    const auto cam = makeCameraModel(p);
    glm::dvec3 org, dir;
    cam->ray(8, 6, 0.5, 0.5, org, dir);
    const double cosA = -dir.z;
    if (angles.y == 0) {
      EXPECT_NEAR(std::acos(cosA) / kDeg, std::abs(angles.x), 1e-9);
    }
    const Framebuffer fb = render(*l.scene, p, kAovDepth | kAovDistance);
    for (size_t i = 0; i < fb.pixelCount(); ++i) {
      ASSERT_TRUE(std::isfinite(fb.depth[i])) << i;
      EXPECT_LE(relErr(fb.depth[i], D), 1e-6) << i;
      // T = D / cos(angle), cos taken from the float direction actually traced.
      EXPECT_LE(relErr(fb.distance[i], D / double(-float(dir.z))), 1e-5) << i;
    }
  }
  CameraParams p;
  p.type = "oblique";
  p.viewport = glm::dvec2(1.0, 1.0);
  p.obliqueAnglesDeg = glm::dvec2(89.0, 0.0);
  EXPECT_THROW(makeCamera(p), Error);
}

TEST(NumericsParallel, OrthographicViewportsOf1e4And1e6Units) {
  const double D = 3.0;
  for (double size : {1e-4, 1e6}) {
    const glm::dvec3 c(5e5, -2e5, 1e3);  // away from the origin too
    LoadOptions lo;
    lo.translate = c;
    const Loaded l = load("procedural:quad?size=" + std::to_string(4 * size) + "&z=0", lo);
    CameraParams p;
    p.type = "orthographic";
    p.eye = c + glm::dvec3(0, 0, D);
    p.dir = glm::dvec3(0, 0, -1);
    p.width = 20;
    p.height = 10;
    p.viewport = glm::dvec2(size, 0.5 * size);
    const Framebuffer fb = render(*l.scene, p, kAovDepth | kAovDistance | kAovPosition);
    for (int i = 0; i < p.height; ++i)
      for (int j = 0; j < p.width; ++j) {
        const size_t px = size_t(i) * size_t(p.width) + size_t(j);
        ASSERT_TRUE(std::isfinite(fb.depth[px]));
        EXPECT_LE(relErr(fb.depth[px], D), 1e-6);
        EXPECT_LE(relErr(fb.distance[px], D), 1e-6);
        // P = e + u·U + v·V − D·W, the nearest float (to within a float ulp of P and of the
        // render-space origin's rounding, which is relative to the viewport).
        const double u = ((j + 0.5) / p.width - 0.5) * size;
        const double v = -((i + 0.5) / p.height - 0.5) * 0.5 * size;
        const glm::dvec3 want = c + glm::dvec3(u, v, 0.0);
        for (int a = 0; a < 3; ++a)
          EXPECT_NEAR(fb.position[3 * px + a], want[a], std::abs(want[a]) * 1.2e-7 + size * 1.2e-7)
              << size << " " << a;
      }
  }
}

}  // namespace
}  // namespace aperture
