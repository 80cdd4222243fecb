#include "cameras/base.h"

#include <cmath>

#include "core/error.h"
#include "core/sampling.h"

namespace aperture {

namespace {
constexpr double kPi = 3.14159265358979323846;
double radians(double deg) { return deg * kPi / 180.0; }
}  // namespace

void resolveImagePlane(const CameraParams& p, double& d, double& vw, double& vh) {
  if (p.width <= 0 || p.height <= 0)
    throw Error(cat("camera: image size ", p.width, "x", p.height, " must be positive"));
  const double aspect = double(p.width) / double(p.height);
  d = p.d.value_or(1.0);
  requireFinite(d, "image-plane distance d");
  if (!(d > 0)) throw Error(cat("camera: image-plane distance d = ", d, " must be > 0"));
  if (p.viewport) {
    vw = p.viewport->x;
    vh = p.viewport->y;
  } else if (p.focalLengthMm) {
    const double f = *p.focalLengthMm;
    requireFinite(f, "focal length");
    if (!(f > 0)) throw Error(cat("camera: focal length ", f, " mm must be > 0"));
    if (!(p.sensorMm.x > 0 && p.sensorMm.y > 0))
      throw Error(cat("camera: sensor ", p.sensorMm.x, "x", p.sensorMm.y, " mm must be > 0"));
    vw = d * p.sensorMm.x / f;
    vh = d * p.sensorMm.y / f;
  } else {
    const double fov = p.fovDeg.value_or(45.0);
    requireFinite(fov, "fov");
    if (!(fov > 0 && fov < 180))
      throw Error(cat("camera: fov ", fov, " degrees must be in (0, 180)"));
    const double extent = 2.0 * d * std::tan(radians(fov) / 2.0);
    switch (p.fovAxis) {
      case FovAxis::X:
        vw = extent;
        vh = extent / aspect;
        break;
      case FovAxis::Y:
        vh = extent;
        vw = extent * aspect;
        break;
      case FovAxis::Diagonal: {
        const double diag = std::hypot(double(p.width), double(p.height));
        vw = extent * p.width / diag;
        vh = extent * p.height / diag;
        break;
      }
    }
  }
  requireFinite(vw, "viewport width");
  requireFinite(vh, "viewport height");
  if (!(vw > 0 && vh > 0))
    throw Error(cat("camera: viewport ", vw, "x", vh, " must be > 0 in both directions"));
}

CameraFrame frameFromParams(const CameraParams& p) {
  if (p.at && p.dir) throw Error("camera: give either a look-at point or a view direction, not both");
  if (p.at) return CameraFrame::fromLookAt(p.eye, *p.at, p.up);
  if (p.dir) return CameraFrame::fromDirection(p.eye, *p.dir, p.up);
  return CameraFrame::fromLookAt(p.eye, glm::dvec3(0.0), p.up);
}

FrameCamera::FrameCamera(const CameraParams& p, const glm::dvec3& renderOrigin,
                         const char* typeName)
    : params_(p), renderOrigin_(renderOrigin), type_(typeName) {
  if (p.spp < 1) throw Error(cat("camera: spp ", p.spp, " must be >= 1"));
  requireFinite(renderOrigin, "render origin");
  frame_ = frameFromParams(p);
  resolveImagePlane(p, d_, vw_, vh_);
  width_ = p.width;
  height_ = p.height;
  spp_ = p.spp;
  renderEye_ = glm::vec3(frame_.e - renderOrigin_);
  viewAxis_ = glm::vec3(-frame_.w);
}

void FrameCamera::samplePosition(int i, int j, int s, double& x, double& y) const {
  double sx, sy;
  stratified2D(uint32_t(j), uint32_t(i), s, spp_, 0, sx, sy);
  x = j + sx;
  y = i + sy;
}

CameraDescription FrameCamera::describe() const {
  CameraDescription c;
  c.type = type_;
  c.eye = frame_.e;
  c.u = frame_.u;
  c.v = frame_.v;
  c.w = frame_.w;
  c.d = d_;
  c.vw = vw_;
  c.vh = vh_;
  c.width = width_;
  c.height = height_;
  c.spp = spp_;
  c.cameraFromWorld = frame_.cameraFromWorld();
  c.ndcFromWorld = ndcFromCamera() * c.cameraFromWorld;
  return c;
}

}  // namespace aperture
