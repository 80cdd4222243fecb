#pragma once
// Helpers for the camera tests: Embree-shaped packet buffers and camera parameter sets.
#include <embree3/rtcore_ray.h>
#include <gtest/gtest.h>

#include <cmath>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/engine/packet.h"
#include "core/util/units.h"

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

}  // namespace aperture::test
