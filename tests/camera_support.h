#pragma once
// Helpers for the camera tests: Embree-shaped packet buffers and camera parameter sets.
#include <embree3/rtcore_ray.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <glm/glm.hpp>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "cameras/models/base.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/aov/framebuffer.h"
#include "core/engine/packet.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/units.h"
#include "tests/support.h"

namespace aperture::test {

/// Angle between two directions, accurate for tiny angles.
inline double angleBetween(const glm::dvec3& a, const glm::dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

/// The fields the packet contract (core/engine/camera.h) fixes for lane k of an unclipped camera:
/// tnear 0, tfar +inf, time 0, mask all ones, id k, flags 0. Call through
/// ASSERT_NO_FATAL_FAILURE.
inline void assertFixedLaneFields(const RayLanes& l, int k) {
  ASSERT_EQ(l.tnear[k], 0.0f);
  ASSERT_EQ(l.tfar[k], INFINITY);
  ASSERT_EQ(l.time[k], 0.0f);
  ASSERT_EQ(l.mask[k], 0xFFFFFFFFu);
  ASSERT_EQ(l.id[k], unsigned(k));
  ASSERT_EQ(l.flags[k], 0u);
}

/// One aligned RTCRayHitN of width 1, 4, 8 or 16 with RayLanes pointing into it.
class PacketBuffer {
 public:
  explicit PacketBuffer(int width) : width_(width) {
    switch (width) {
      case 1:
        lanes_ = bind(one_, 1);
        break;
      case 4:
        lanes_ = bind(four_, 4);
        break;
      case 8:
        lanes_ = bind(eight_, 8);
        break;
      case 16:
        lanes_ = bind(sixteen_, 16);
        break;
      default:
        ADD_FAILURE() << "bad packet width " << width;
    }
  }
  RayLanes& lanes() { return lanes_; }
  int width() const { return width_; }

 private:
  template <class R>
  static RayLanes bindArrays(R& ray, int width) {
    RayLanes l;
    l.width = width;
    l.orgX = ray.org_x;
    l.orgY = ray.org_y;
    l.orgZ = ray.org_z;
    l.tnear = ray.tnear;
    l.dirX = ray.dir_x;
    l.dirY = ray.dir_y;
    l.dirZ = ray.dir_z;
    l.time = ray.time;
    l.tfar = ray.tfar;
    l.mask = ray.mask;
    l.id = ray.id;
    l.flags = ray.flags;
    return l;
  }
  static RayLanes bind(RTCRayHit& h, int) {
    RayLanes l;
    l.width = 1;
    l.orgX = &h.ray.org_x;
    l.orgY = &h.ray.org_y;
    l.orgZ = &h.ray.org_z;
    l.tnear = &h.ray.tnear;
    l.dirX = &h.ray.dir_x;
    l.dirY = &h.ray.dir_y;
    l.dirZ = &h.ray.dir_z;
    l.time = &h.ray.time;
    l.tfar = &h.ray.tfar;
    l.mask = &h.ray.mask;
    l.id = &h.ray.id;
    l.flags = &h.ray.flags;
    return l;
  }
  template <class H>
  static RayLanes bind(H& h, int width) {
    return bindArrays(h.ray, width);
  }

  int width_;
  RayLanes lanes_{};
  RTCRayHit one_{};
  RTCRayHit4 four_{};
  RTCRayHit8 eight_{};
  RTCRayHit16 sixteen_{};
};

/// Block shape of a packet width, as the frame loop uses them (core/engine/packet.h).
inline void blockShape(int width, int& blockW, int& blockH) {
  blockW = blockWidthFor(width);
  blockH = blockHeightFor(width);
}

/// A generic, non-axis-aligned frame used by many tests.
inline CameraParams tiltedParams(const char* type) {
  CameraParams p;
  p.type = type;
  p.eye = {1.25, -0.5, 3.0};
  p.at = glm::dvec3(-0.75, 0.25, -2.0);
  p.up = {0.1, 1.0, 0.2};
  return p;
}

/// Calibrated intrinsics in everyCamera() are fractions of the image size (fx, cx of the width,
/// fy, cy of the height): this scales them to p's size.
inline CameraParams sizedCamera(CameraParams p) {
  if (p.intrinsics) {
    std::vector<double>& k = *p.intrinsics;
    k = {k[0] * p.width, k[1] * p.height, k[2] * p.width, k[3] * p.height};
  }
  return p;
}

/// Parameters of every model in a usable configuration (shifted and lens cases included).
inline std::vector<CameraParams> everyCamera() {
  std::vector<CameraParams> all;
  CameraParams p = tiltedParams("perspective");
  p.fovDeg = 50;
  all.push_back(p);
  p.shift = {0.2, -0.35};
  all.push_back(p);
  p.shift = {0.0, 0.0};
  p.architectural = true;
  all.push_back(p);
  CameraParams o = tiltedParams("orthographic");
  o.viewport = glm::dvec2(3.0, 2.0);
  all.push_back(o);
  o.type = "oblique";
  o.obliqueAnglesDeg = glm::dvec2(30.0, -20.0);
  all.push_back(o);
  CameraParams t = tiltedParams("thinlens");
  t.fovDeg = 40;
  t.apertureRadius = 0.2;
  t.focusDistance = 4.0;
  all.push_back(t);
  CameraParams e = tiltedParams("equirect");
  all.push_back(e);
  e.longitudeRangeDeg = {-60.0, 100.0};
  e.latitudeRangeDeg = {-30.0, 45.0};
  all.push_back(e);
  CameraParams f = tiltedParams("fisheye");
  f.fisheyeFovDeg = 200;
  all.push_back(f);
  // Calibrated: a distorted OPENCV lens with the principal point off-centre, and a 190°
  // OPENCV_FISHEYE (pixels past its circle have no ray). Sizes are set by the tests.
  CameraParams c = tiltedParams("calibrated");
  c.lensModel = "OPENCV";
  c.intrinsics = std::vector<double>{0.9, 0.8, 0.55, 0.45};  // times width and height below
  c.distortion = std::vector<double>{-0.2, 0.05, 1e-3, -5e-4};
  all.push_back(c);
  c.lensModel = "OPENCV_FISHEYE";
  c.intrinsics = std::vector<double>{0.3, 0.3, 0.5, 0.5};
  c.distortion = std::vector<double>{0.0, 0.0, 0.0, 0.0};
  all.push_back(c);
  return all;
}

/// Degrees to radians.
inline double rad(double deg) { return deg * kPi / 180.0; }

/// The camera model of `p` (the registry's makeCameraModel).
inline std::unique_ptr<CameraBase> make(const CameraParams& p,
                                        const glm::dvec3& renderOrigin = glm::dvec3(0.0)) {
  return makeCameraModel(p, renderOrigin);
}

inline glm::dvec3 toDouble(const glm::vec3& v) { return glm::dvec3(v); }

/// Generates the single-pixel packet (1x1) for pixel (i, j), sample s.
struct Lane {
  glm::vec3 org, dir;
  int valid;
};
inline Lane pixelLane(const Camera& cam, int i, int j, int s = 0) {
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

// ---- camera files (tests/cameras/files) ----

/// Expects `call` to throw an Error whose message holds every one of the strings that follow.
#define EXPECT_ERROR_MENTIONS(call, ...)                                  \
  do {                                                                    \
    const std::string message = ::aperture::test::errorOf([&] { call; }); \
    ASSERT_FALSE(message.empty()) << #call " did not throw";              \
    for (const std::string& part : std::vector<std::string>{__VA_ARGS__}) \
      EXPECT_NE(message.find(part), std::string::npos)                    \
          << "'" << part << "' is missing from: " << message;             \
  } while (0)

inline glm::dvec3 apply(const glm::dmat4& m, const glm::dvec3& p) {
  return glm::dvec3(m * glm::dvec4(p, 1));
}

// Rotation of (row, col) of a GLM matrix, row-major reading.
inline double rc(const glm::dmat4& m, int row, int col) { return m[col][row]; }

inline void expectSameFile(const CameraFile& a, const CameraFile& b) {
  ASSERT_EQ(a.sensors.size(), b.sensors.size());
  for (size_t s = 0; s < a.sensors.size(); ++s) {
    EXPECT_TRUE(a.sensors[s] == b.sensors[s]) << "sensor " << s;
    EXPECT_EQ(a.sensors[s].lens.params(), b.sensors[s].lens.params()) << "sensor " << s;
  }
  EXPECT_EQ(a.sensorIds, b.sensorIds);
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t k = 0; k < a.images.size(); ++k) {
    EXPECT_EQ(a.images[k].name, b.images[k].name);
    EXPECT_EQ(a.images[k].sensor, b.images[k].sensor);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        EXPECT_EQ(a.images[k].cvCameraFromWorld[c][r], b.images[k].cvCameraFromWorld[c][r])
            << "image " << k << " (row " << r << ", column " << c << ")";
  }
}

inline void expectSamePoses(const CameraFile& a, const CameraFile& b, double tolerance) {
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t k = 0; k < a.images.size(); ++k)
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        EXPECT_NEAR(a.images[k].cvCameraFromWorld[c][r], b.images[k].cvCameraFromWorld[c][r],
                    tolerance)
            << "image " << k << " (row " << r << ", column " << c << ")";
}

// ---- calibrated renders of the bunny (tests/cameras/models/test_calibrated_render*.cpp) ----

/// The bunny, loaded and built once for the whole test binary (members destroyed in reverse
/// order).
struct Bunny {
  Mesh mesh;
  Device device;
  std::unique_ptr<Scene> scene;
};

inline const Scene& bunnyScene(const std::string& path) {
  static std::unique_ptr<Bunny> bunny;
  if (!bunny) {
    bunny = std::make_unique<Bunny>();
    bunny->mesh = loadMesh(path);
    bunny->scene = std::make_unique<Scene>(bunny->device, std::vector<const Mesh*>{&bunny->mesh});
  }
  return *bunny->scene;
}

#define REQUIRE_BUNNY(scene)                                           \
  APERTURE_REQUIRE_SHARED_MESH(bunnyPath_, "stanford/bun_zipper.ply"); \
  const Scene& scene = ::aperture::test::bunnyScene(bunnyPath_)

/// Every AOV of the camera `p` on `scene`, traced `packetWidth` rays at a time. Named apart
/// from test::render, which takes an AovMask.
inline Framebuffer renderAllAovs(const Scene& scene, const CameraParams& p, int packetWidth = 16) {
  const std::unique_ptr<Camera> camera = makeCamera(p, scene.renderOrigin());
  RenderSettings settings;
  settings.packetWidth = packetWidth;
  Framebuffer fb(
      p.width, p.height,
      kAovColor | kAovDepth | kAovDistance | kAovNormal | kAovPosition | kAovPrimId | kAovGeomId);
  renderImage(scene, *camera, settings, fb);
  return fb;
}

inline glm::dvec3 positionAt(const Framebuffer& fb, size_t k) {
  return {fb.position[3 * k], fb.position[3 * k + 1], fb.position[3 * k + 2]};
}

// ---- poses, written out here from eye / at / up ----

/// The lecture frame: W = −view, U = up × W, V = W × U (all unit).
struct Frame {
  glm::dvec3 e, u, v, w;
};
inline Frame frameOf(const glm::dvec3& eye, const glm::dvec3& at, const glm::dvec3& up) {
  Frame f;
  f.e = eye;
  f.w = glm::normalize(eye - at);
  f.u = glm::normalize(glm::cross(up, f.w));
  f.v = glm::cross(f.w, f.u);
  return f;
}

// Reference views of the bunny (its README): from the front, a little rolled so that no
// rotation entry is zero; fisheyes closer, so that the bunny fills more of their wide view.
inline const glm::dvec3 kBunnyAt(-0.017, 0.11, 0.0);
inline const glm::dvec3 kRolledUp(0.15, 1.0, 0.05);
inline Frame perspectiveView() { return frameOf({-0.02, 0.11, 0.35}, kBunnyAt, kRolledUp); }

// ---- re-projection ----

/// Distances between where hit points re-project and the centres of their pixels.
struct Reprojection {
  size_t hits = 0;
  size_t unprojected = 0;  ///< hits whose P the projection gives no position (counted as +inf)
  double p99 = std::numeric_limits<double>::infinity(),
         max = std::numeric_limits<double>::infinity();
  std::string text() const {
    char s[160];
    std::snprintf(s, sizeof s, "%zu hits, p99 %.3g px, max %.3g px, %zu without a projection", hits,
                  p99, max, unprojected);
    return s;
  }
};

/// `project` maps a world point to aperture's raster (pixel (i, j) centre at (j + ½, i + ½)).
using Projection = std::function<std::optional<glm::dvec2>(const glm::dvec3&)>;

inline Reprojection reprojection(const Framebuffer& fb, const Projection& project) {
  std::vector<double> errors;
  Reprojection r;
  for (int i = 0; i < fb.height; ++i)
    for (int j = 0; j < fb.width; ++j) {
      const size_t k = size_t(i) * size_t(fb.width) + size_t(j);
      if (fb.primId[k] == kInvalidId) continue;
      const std::optional<glm::dvec2> x = project(positionAt(fb, k));
      r.unprojected += !x;
      errors.push_back(x ? glm::length(*x - glm::dvec2(j + 0.5, i + 0.5))
                         : std::numeric_limits<double>::infinity());
    }
  r.hits = errors.size();
  if (errors.empty()) return r;
  std::sort(errors.begin(), errors.end());
  r.p99 = errors[size_t(std::ceil(0.99 * double(errors.size()))) - 1];
  r.max = errors.back();
  return r;
}

inline CameraParams paramsOfImage(const CameraFile& file, size_t k) {
  const CalibratedImage& im = file.images.at(k);
  return calibratedCameraParams(file.sensors.at(size_t(im.sensor)), im.cvCameraFromWorld);
}

// ---- the command line (tests/apps/cli/test_camera_files_cli*.cpp) ----

/// Every file below `dir`, relative, sorted.
inline std::set<std::string> filesBelow(const std::string& dir) {
  std::set<std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    files.insert(std::filesystem::relative(e.path(), dir).generic_string());
  return files;
}

/// Runs a command that must be refused: non-zero exit (not a signal), every part of `expect`
/// in its output, and no file added below `dir`.
inline void expectRefused(const std::string& command, const std::vector<std::string>& expect,
                          const std::string& dir) {
  SCOPED_TRACE(command);
  const std::set<std::string> before = filesBelow(dir);
  std::string out;
  const int code = runCommand(command, &out);
  EXPECT_GT(code, 0) << out;
  for (const std::string& e : expect)
    EXPECT_NE(out.find(e), std::string::npos) << "'" << e << "' is missing from: " << out;
  EXPECT_EQ(filesBelow(dir), before) << "a refused run wrote files";
}

}  // namespace aperture::test
