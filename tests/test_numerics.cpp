// Numerical stability at the extremes (issue 5, items 5 and 6): far-from-origin scenes,
// extreme fields of view, near-degenerate frames, scaled image planes, tiny lenses, oblique
// and orthographic extremes, depth precision, watertightness, non-finite input, determinism.
// Each test checks a closed form or an independent path; the world-space float32 mode's
// errors are measured and printed (docs/numerics.md records them), not asserted.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include "cameras/base.h"
#include "cameras/registry.h"
#include "core/error.h"
#include "core/exr.h"
#include "core/mesh.h"
#include "core/render.h"
#include "core/scene.h"
#include "core/trace.h"
#include "tests/support.h"

namespace aperture {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

Device& device() {
  static Device d;
  return d;
}

/// A loaded mesh and the scene over it (the mesh must outlive the scene).
struct Loaded {
  std::unique_ptr<Mesh> mesh;
  std::unique_ptr<Scene> scene;
};

Loaded load(const std::string& spec, const LoadOptions& lo = {}, const BuildOptions& bo = {}) {
  Loaded l;
  l.mesh = std::make_unique<Mesh>(loadMesh(spec, lo));
  l.scene = std::make_unique<Scene>(device(), std::vector<const Mesh*>{l.mesh.get()}, bo);
  return l;
}

Framebuffer render(const Scene& scene, const CameraParams& p, AovMask aovs,
                   RenderStats* stats = nullptr) {
  const auto cam = makeCamera(p, scene.renderOrigin());
  Framebuffer fb(p.width, p.height, aovs);
  RenderSettings rs;
  rs.spp = p.spp;
  const RenderStats s = renderFrame(scene, *cam, rs, fb);
  if (stats) *stats = s;
  return fb;
}

CameraParams lookAt(glm::dvec3 eye, glm::dvec3 at, int w, int h) {
  CameraParams p;
  p.eye = eye;
  p.at = at;
  p.width = w;
  p.height = h;
  p.fovDeg = 40;
  return p;
}

double relErr(double got, double want) { return std::abs(got - want) / std::abs(want); }

/// Agreement of two renders: share of pixels with equal primID and the largest relative Z / T
/// error over the pixels both hit on the same triangle.
struct Agreement {
  double primIdShare = 0, maxZ = 0, maxT = 0;
};

Agreement compare(const Framebuffer& a, const Framebuffer& ref) {
  Agreement g;
  size_t same = 0;
  for (size_t i = 0; i < ref.pixelCount(); ++i) {
    if (a.primId[i] != ref.primId[i]) continue;
    ++same;
    if (ref.primId[i] == kInvalidId) continue;
    g.maxZ = std::max(g.maxZ, relErr(a.depth[i], ref.depth[i]));
    g.maxT = std::max(g.maxT, relErr(a.distance[i], ref.distance[i]));
  }
  g.primIdShare = double(same) / double(ref.pixelCount());
  return g;
}

// --- Translation invariance ------------------------------------------------------------

// The city and its camera moved by T (in double: LoadOptions.translate and eye/at + T).
// Camera-relative: the mesh is stored relative to its bounding-box centre and the camera's
// origin is computed in double relative to it, so the image must not change. World-space:
// float32 world coordinates; the error grows with T and is printed, not asserted.
TEST(NumericsTranslation, CameraRelativeIsInvariantWorldSpaceErrorIsMeasured) {
  const AovMask aovs = kAovDepth | kAovDistance | kAovPrimId;
  const glm::dvec3 dirT = glm::normalize(glm::dvec3(1.0, 0.5, -0.75));
  auto renderAt = [&](double t, Placement placement) {
    LoadOptions lo;
    lo.placement = placement;
    lo.translate = t * dirT;
    const Loaded l = load("procedural:city", lo);
    CameraParams p = lookAt(glm::dvec3(14, 11, 18) + t * dirT, glm::dvec3(0, 1, 0) + t * dirT,
                            192, 128);
    return render(*l.scene, p, aovs);
  };
  const Framebuffer ref = renderAt(0.0, Placement::CameraRelative);
  std::printf("[ info ] translation T | mode            | primID agree | max rel Z  | max rel T\n");
  for (double t : {1e3, 1e5, 1e6, 1e7}) {
    for (Placement pl : {Placement::CameraRelative, Placement::WorldSpace}) {
      const Agreement g = compare(renderAt(t, pl), ref);
      const bool rel = pl == Placement::CameraRelative;
      std::printf("[ info ] %13.0e | %-15s | %11.4f%% | %10.3e | %10.3e\n", t,
                  rel ? "camera-relative" : "world-space", 100.0 * g.primIdShare, g.maxZ,
                  g.maxT);
      if (rel) {
        EXPECT_GE(g.primIdShare, 0.999) << "T = " << t;
        EXPECT_LE(g.maxZ, 1e-5) << "T = " << t;
        EXPECT_LE(g.maxT, 1e-5) << "T = " << t;
      }
    }
  }
}

// The header and P of a far render: P is reconstructed in double (render origin + org + t·dir)
// and rounded once, so it is as exact as float allows at 1e7.
TEST(NumericsTranslation, PositionAtOneE7IsTheNearestFloatOfTheHitPoint) {
  const double t = 1e7;
  LoadOptions lo;
  lo.translate = glm::dvec3(t, t, t);
  const Loaded l = load("procedural:quad?size=4&z=0", lo);  // plane z = 1e7
  CameraParams p = lookAt(glm::dvec3(t, t, t + 3), glm::dvec3(t, t, t), 32, 32);
  const Framebuffer fb = render(*l.scene, p, kAovPosition | kAovDepth);
  for (size_t i = 0; i < fb.pixelCount(); ++i) {
    ASSERT_EQ(fb.position[3 * i + 2], float(t)) << i;
    EXPECT_NEAR(fb.depth[i], 3.0, 3.0 * 1e-6);
  }
}

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
    cam.generate(PacketRequest{x0, row, 16, 1, 0}, lanes, valid);
    for (int k = 0; k < 16 && x0 + k < width; ++k)
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
  const auto cam = makeFrameCamera(p);
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
  const auto rotated = makeFrameCamera(p);
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
  const auto cam = makeFrameCamera(p);
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
      const auto cam = makeFrameCamera(p);
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
  EXPECT_THROW(CameraFrame::fromDirection(eye, glm::dvec3(nan, 0, -1), glm::dvec3(0, 1, 0)),
               Error);
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
    const auto cam = makeFrameCamera(p);
    glm::dvec3 org, dir;
    cam->ray(0.0, 0.5 * c.h, 0.5, 0.5, org, dir);
    EXPECT_NEAR(std::atan2(-dir.x, -dir.z), std::atan(0.5 * c.viewport.x), 1e-12);
  }
}

// --- Thin lens -------------------------------------------------------------------------

TEST(NumericsThinLens, TinyApertureEqualsThePinholeWithinFloatError) {
  const Loaded l = load("procedural:city");
  CameraParams pin = lookAt(glm::dvec3(14, 11, 18), glm::dvec3(0, 1, 0), 128, 96);
  pin.spp = 4;  // the same pixel positions as the lens camera's (geometry AOVs: sample 0)
  CameraParams lens = pin;
  lens.type = "thinlens";
  lens.apertureRadius = 1e-9;
  lens.focusDistance = 20.0;
  const auto a = makeFrameCamera(pin, l.scene->renderOrigin());
  const auto b = makeFrameCamera(lens, l.scene->renderOrigin());
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
          for (int c = 0; c < 3; ++c)
            EXPECT_LE(std::abs(float(db[c]) - float(da[c])), 6e-8f);
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
    const auto cam = makeFrameCamera(p, glm::dvec3(1e3, -2e3, 0));
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
  for (glm::dvec2 angles : {glm::dvec2(88.9, 0), glm::dvec2(0, -88.9), glm::dvec2(60, 60),
                            glm::dvec2(-45, 30)}) {
    CameraParams p;
    p.type = "oblique";
    p.eye = glm::dvec3(0, 0, D);
    p.dir = glm::dvec3(0, 0, -1);
    p.width = 16;
    p.height = 12;
    p.viewport = glm::dvec2(1.0, 0.75);
    p.obliqueAnglesDeg = angles;
    const auto cam = makeFrameCamera(p);
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
          EXPECT_NEAR(fb.position[3 * px + a], want[a],
                      std::abs(want[a]) * 1.2e-7 + size * 1.2e-7)
              << size << " " << a;
      }
  }
}

// --- Depth precision -------------------------------------------------------------------

TEST(NumericsDepth, PlanesFrom1e2To1e6GiveZAndTWithin1e6StoredAsFloat32) {
  const std::string dir = test::scratchDir();
  for (double D : {1e-2, 1.0, 1e2, 1e4, 1e6}) {
    // A plane at depth D, wide enough for a 40° field.
    const Loaded l = load("procedural:quad?size=" + std::to_string(4 * D) + "&z=" +
                          std::to_string(-D));
    CameraParams p;
    p.eye = glm::dvec3(0.0);
    p.dir = glm::dvec3(0, 0, -1);
    p.width = 24;
    p.height = 16;
    p.fovDeg = 40;
    const Framebuffer fb = render(*l.scene, p, kAovColor | kAovDepth | kAovDistance);
    const auto cam = makeFrameCamera(p, l.scene->renderOrigin());
    double maxZ = 0, maxT = 0;
    for (int i = 0; i < p.height; ++i)
      for (int j = 0; j < p.width; ++j) {
        const size_t px = size_t(i) * size_t(p.width) + size_t(j);
        glm::dvec3 org, d;
        cam->ray(j + 0.5, i + 0.5, 0.5, 0.5, org, d);
        const glm::dvec3 df = glm::dvec3(glm::vec3(d));  // the float direction traced
        maxZ = std::max(maxZ, relErr(fb.depth[px], D));
        maxT = std::max(maxT, relErr(fb.distance[px], D / -df.z));
      }
    EXPECT_LE(maxZ, 1e-6) << "D = " << D;
    EXPECT_LE(maxT, 1e-6) << "D = " << D;
    std::printf("[ info ] plane at %g: max rel error Z %.2e, T %.2e\n", D, maxZ, maxT);

    // Stored float32 even with half color, and read back exactly.
    const std::string path = dir + "/d.exr";
    ExrMetadata meta;
    meta.camera = cam->describe();
    ExrOptions opt;
    opt.halfColor = true;
    writeExr(path, fb, meta, opt);
    Imf::InputFile file(path.c_str());
    const Imf::ChannelList& ch = file.header().channels();
    ASSERT_NE(ch.findChannel("Z"), nullptr);
    ASSERT_NE(ch.findChannel("T"), nullptr);
    EXPECT_EQ(ch.findChannel("Z")->type, Imf::FLOAT);
    EXPECT_EQ(ch.findChannel("T")->type, Imf::FLOAT);
    EXPECT_EQ(ch.findChannel("R")->type, Imf::HALF);
    const Framebuffer back = readExr(path);
    EXPECT_EQ(0, std::memcmp(back.depth.data(), fb.depth.data(), fb.depth.size() * 4));
    EXPECT_EQ(0, std::memcmp(back.distance.data(), fb.distance.data(), fb.distance.size() * 4));
  }
}

// --- Watertightness --------------------------------------------------------------------

struct WatertightCounts {
  size_t edgeRays = 0, edgeMisses = 0, vertexRays = 0, vertexMisses = 0;
};

// Rays aimed exactly (in render space, as float) at points of shared edges and at vertices of
// a closed mesh, from outside along the outward direction through the mesh's centre: each
// such ray passes through the interior, so a watertight intersector must hit something.
WatertightCounts shootAtEdgesAndVertices(const Mesh& m, const Scene& scene) {
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  const glm::dvec3 centre = 0.5 * (glm::dvec3(lo) + glm::dvec3(hi));
  const double reach = glm::length(glm::dvec3(hi) - glm::dvec3(lo));
  // The anchor of the mesh relative to the scene's render origin (0 in camera-relative mode).
  const glm::dvec3 shift = m.anchor - scene.renderOrigin();
  auto aim = [&](const glm::dvec3& target, std::vector<TraceRay>& rays) {
    const glm::dvec3 out = glm::normalize(target - centre);
    TraceRay r;
    r.org = glm::vec3(shift + target + reach * out);
    // Aim from the rounded origin at the target itself, so the ray passes through it.
    r.dir = glm::vec3(glm::normalize((shift + target) - glm::dvec3(r.org)));
    rays.push_back(r);
  };
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    for (int e = 0; e < 3; ++e) {
      uint32_t a = m.indices[3 * t + size_t(e)], b = m.indices[3 * t + size_t((e + 1) % 3)];
      if (a > b) std::swap(a, b);
      ++edges[{a, b}];
    }
  std::vector<TraceRay> edgeRays, vertexRays;
  for (const auto& [e, uses] : edges) {
    if (uses != 2) continue;  // shared edges only
    const glm::dvec3 a(m.vertex(e.first)), b(m.vertex(e.second));
    for (double s : {0.5, 0.25, 0.125, 0.999})
      aim(a + s * (b - a), edgeRays);
  }
  for (size_t v = 0; v < m.vertexCount; ++v) aim(glm::dvec3(m.vertex(v)), vertexRays);
  WatertightCounts c;
  for (const TraceHit& h : traceRays(scene, edgeRays)) c.edgeMisses += !h.hit();
  for (const TraceHit& h : traceRays(scene, vertexRays)) c.vertexMisses += !h.hit();
  c.edgeRays = edgeRays.size();
  c.vertexRays = vertexRays.size();
  return c;
}

TEST(NumericsWatertight, RobustHasNoEdgeMissesFarFromTheOriginVertexMissesAreCounted) {
  std::printf("[ info ] mesh at 1e6          | placement       | robust | edge misses | "
              "vertex misses\n");
  for (const char* spec : {"procedural:sphere?radius=3&segments=48&rings=24",
                           "procedural:cube?size=2"}) {
    for (Placement pl : {Placement::CameraRelative, Placement::WorldSpace}) {
      for (bool robust : {true, false}) {
        LoadOptions lo;
        lo.placement = pl;
        lo.translate = glm::dvec3(1e6, -1e6, 1e6);
        BuildOptions bo;
        bo.robust = robust;
        const Loaded l = load(spec, lo, bo);
        const WatertightCounts c = shootAtEdgesAndVertices(*l.mesh, *l.scene);
        ASSERT_GT(c.edgeRays, 0u);
        std::printf("[ info ] %-20.20s | %-15s | %-6s | %5zu / %-5zu | %4zu / %zu\n",
                    spec + 11, pl == Placement::WorldSpace ? "world-space" : "camera-relative",
                    robust ? "yes" : "no", c.edgeMisses, c.edgeRays, c.vertexMisses,
                    c.vertexRays);
        if (robust) {
          EXPECT_EQ(c.edgeMisses, 0u) << spec;
        }
      }
    }
  }
}

// The trace API agrees with the frame loop: the centre pixel's ray hits the same triangle at
// the same distance.
TEST(NumericsWatertight, TraceRaysMatchesTheFrameLoop) {
  const Loaded l = load("procedural:city");
  CameraParams p = lookAt(glm::dvec3(14, 11, 18), glm::dvec3(0, 1, 0), 33, 17);
  const Framebuffer fb = render(*l.scene, p, kAovDistance | kAovPrimId);
  const auto cam = makeFrameCamera(p, l.scene->renderOrigin());
  std::vector<TraceRay> rays;
  for (int i = 0; i < p.height; ++i)
    for (int j = 0; j < p.width; ++j) {
      glm::dvec3 o, d;
      cam->ray(j + 0.5, i + 0.5, 0.5, 0.5, o, d);
      rays.push_back({glm::vec3(o), glm::vec3(d)});
    }
  for (int width : {1, 4, 8, 16}) {
    const std::vector<TraceHit> hits = traceRays(*l.scene, rays, width);
    for (size_t i = 0; i < hits.size(); ++i) {
      EXPECT_EQ(hits[i].primId, fb.primId[i]) << i;
      if (hits[i].hit()) {
        EXPECT_EQ(hits[i].t, fb.distance[i]) << i;
      }
    }
  }
  EXPECT_THROW(traceRays(*l.scene, rays, 3), Error);
  TraceRay bad;
  bad.dir = glm::vec3(std::numeric_limits<float>::quiet_NaN(), 0, -1);
  EXPECT_FALSE(traceRays(*l.scene, {bad})[0].hit());
}

// --- Non-finite input ------------------------------------------------------------------

TEST(NumericsNonFinite, NanAndInfVerticesAreDroppedAndCountedThroughTheRenderer) {
  const std::string dir = test::scratchDir();
  // Two quads facing +z: the left one (x < 0) uses a NaN and an Inf vertex.
  test::writeFile(dir + "/bad.ply",
                  "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                  "end_header\n"
                  "-2 -1 0\n0 -1 0\nnan 1 0\n-2 1 inf\n"
                  "0 -1 0\n2 -1 0\n2 1 0\n0 1 0\n"
                  "3 0 1 2\n3 0 2 3\n3 4 5 6\n3 4 6 7\n");
  std::string out;
  const std::string cmd = test::apertureBinary() + " render --mesh " + dir +
                          "/bad.ply --eye 0,0,6 --at 0,0,0 --size 40,20 --fov 40 --aov "
                          "depth,primid --out " + dir + "/bad.exr";
  ASSERT_EQ(test::runCommand(cmd, &out), 0) << out;
  EXPECT_NE(out.find("2 non-finite vertices, 2 triangles dropped"), std::string::npos) << out;
  const Framebuffer fb = readExr(dir + "/bad.exr");
  size_t left = 0, right = 0;
  for (int i = 0; i < fb.height; ++i)
    for (int j = 0; j < fb.width; ++j) {
      const size_t px = size_t(i) * size_t(fb.width) + size_t(j);
      ASSERT_FALSE(std::isnan(fb.depth[px]));
      if (fb.primId[px] == kInvalidId) continue;
      EXPECT_LT(fb.primId[px], 2u);  // the two finite triangles, renumbered 0 and 1
      (j < fb.width / 2 ? left : right)++;
    }
  EXPECT_EQ(left, 0u);
  EXPECT_GT(right, 0u);
}

TEST(NumericsNonFinite, NonFiniteCameraParametersAreErrors) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto base = [] {
    CameraParams p;
    p.eye = glm::dvec3(0, 0, 5);
    p.at = glm::dvec3(0.0);
    p.width = 8;
    p.height = 8;
    return p;
  };
  std::vector<CameraParams> bad;
  for (double x : {nan, inf, -inf}) {
    CameraParams p = base();
    p.eye.y = x;
    bad.push_back(p);
    p = base();
    p.at = glm::dvec3(x, 0, 0);
    bad.push_back(p);
    p = base();
    p.up = glm::dvec3(0, x, 0);
    bad.push_back(p);
    p = base();
    p.fovDeg = x;
    bad.push_back(p);
    p = base();
    p.d = x;
    p.viewport = glm::dvec2(1, 1);
    bad.push_back(p);
    p = base();
    p.viewport = glm::dvec2(x, 1);
    bad.push_back(p);
    p = base();
    p.shift = glm::dvec2(0, x);
    bad.push_back(p);
    p = base();
    p.type = "thinlens";
    p.apertureRadius = x;
    bad.push_back(p);
    p = base();
    p.type = "thinlens";
    p.apertureRadius = 0.1;
    p.focusDistance = x;
    bad.push_back(p);
    p = base();
    p.type = "oblique";
    p.viewport = glm::dvec2(1, 1);
    p.obliqueAnglesDeg = glm::dvec2(x, 0);
    bad.push_back(p);
  }
  for (size_t k = 0; k < bad.size(); ++k) EXPECT_THROW(makeCamera(bad[k]), Error) << k;
  // A non-finite render origin (a broken anchor) is an error too.
  EXPECT_THROW(makeCamera(base(), glm::dvec3(nan, 0, 0)), Error);
  // And on the command line.
  std::string out;
  EXPECT_NE(test::runCommand(test::apertureBinary() + " render --eye nan,0,5 --size 8,8 --out " +
                                 test::scratchDir() + "/x.exr",
                             &out),
            0);
  EXPECT_NE(out.find("--eye"), std::string::npos) << out;
}

/// A camera whose rays are those of a real one except that some lanes get a NaN or an Inf
/// (in the direction or the origin): the frame loop must not trace them.
class PoisonedCamera final : public Camera {
 public:
  explicit PoisonedCamera(std::unique_ptr<Camera> inner) : inner_(std::move(inner)) {}
  static bool poisoned(int i, int j) { return (i * 7 + j * 3) % 5 == 0; }
  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    inner_->generate(req, out, valid);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    for (int k = 0; k < req.blockW * req.blockH; ++k) {
      const int i = req.y0 + k / req.blockW, j = req.x0 + k % req.blockW;
      if (!poisoned(i, j)) continue;
      switch ((i + j) % 3) {
        case 0: out.dirX[k] = nan; break;
        case 1: out.orgZ[k] = -inf; break;
        default: out.dirZ[k] = inf; break;
      }
    }
  }
  glm::vec3 renderEye() const override { return inner_->renderEye(); }
  glm::vec3 viewAxis() const override { return inner_->viewAxis(); }
  CameraDescription describe() const override { return inner_->describe(); }
  bool stochastic() const override { return inner_->stochastic(); }

 private:
  std::unique_ptr<Camera> inner_;
};

TEST(NumericsNonFinite, NonFiniteRaysAreNeverTracedAndNeverReachTheFramebuffer) {
  const Loaded l = load("procedural:quad?size=100&z=0");
  CameraParams p;
  p.eye = glm::dvec3(0, 0, 4);
  p.at = glm::dvec3(0.0);
  p.width = 37;
  p.height = 23;
  for (int spp : {1, 4}) {
    p.spp = spp;
    for (int packet : {1, 4, 8, 16}) {
      const PoisonedCamera cam(makeCamera(p, l.scene->renderOrigin()));
      Framebuffer fb(p.width, p.height, parseAovList("all"));
      RenderSettings rs;
      rs.packetWidth = packet;
      rs.spp = spp;
      const RenderStats stats = renderFrame(*l.scene, cam, rs, fb);
      size_t bad = 0;
      for (int i = 0; i < p.height; ++i)
        for (int j = 0; j < p.width; ++j) {
          const size_t px = size_t(i) * size_t(p.width) + size_t(j);
          if (!PoisonedCamera::poisoned(i, j)) {
            EXPECT_NE(fb.primId[px], kInvalidId);
            continue;
          }
          ++bad;
          EXPECT_EQ(fb.primId[px], kInvalidId);
          EXPECT_EQ(fb.geomId[px], kInvalidId);
          EXPECT_EQ(fb.depth[px], std::numeric_limits<float>::infinity());
          EXPECT_EQ(fb.distance[px], std::numeric_limits<float>::infinity());
          for (int c = 0; c < 4; ++c) EXPECT_EQ(fb.rgba[4 * px + size_t(c)], 0.0f);
          for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(fb.normal[3 * px + size_t(c)], 0.0f);
            EXPECT_EQ(fb.position[3 * px + size_t(c)], 0.0f);
          }
        }
      EXPECT_EQ(stats.raysSkipped, uint64_t(bad) * uint64_t(spp));
      EXPECT_EQ(stats.raysTraced, uint64_t(fb.pixelCount() - bad) * uint64_t(spp));
      for (float v : fb.rgba) EXPECT_TRUE(std::isfinite(v));
    }
  }
}

// --- Determinism -----------------------------------------------------------------------

TEST(NumericsDeterminism, TheSameRenderCommandThreeTimesGivesBitIdenticalPixels) {
  const std::string dir = test::scratchDir();
  std::vector<Framebuffer> runs;
  for (int k = 0; k < 3; ++k) {
    const std::string path = dir + "/run" + std::to_string(k) + ".exr";
    std::string out;
    ASSERT_EQ(test::runCommand(test::apertureBinary() +
                                   " render --mesh procedural:city --camera thinlens --aperture "
                                   "0.2 --focus 15 --spp 4 --eye 14,11,18 --at 0,1,0 --size "
                                   "96,64 --aov all --threads 2 --quiet --out " + path,
                               &out),
              0)
        << out;
    runs.push_back(readExr(path));
  }
  // The header holds the render time, so the files differ; the pixels must not.
  for (int k = 1; k < 3; ++k) {
    const Framebuffer &a = runs[0], &b = runs[size_t(k)];
    auto same = [](const auto& x, const auto& y) {
      return x.size() == y.size() &&
             std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
    };
    EXPECT_TRUE(same(a.rgba, b.rgba));
    EXPECT_TRUE(same(a.depth, b.depth));
    EXPECT_TRUE(same(a.distance, b.distance));
    EXPECT_TRUE(same(a.normal, b.normal));
    EXPECT_TRUE(same(a.position, b.position));
    EXPECT_TRUE(same(a.primId, b.primId));
    EXPECT_TRUE(same(a.geomId, b.geomId));
    EXPECT_FALSE(a.rgba.empty());
  }
}

}  // namespace
}  // namespace aperture
