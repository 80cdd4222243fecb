#include "cameras/geometry/frame.h"

#include <cmath>

#include "core/engine/camera.h"
#include "core/util/error.h"

namespace aperture {

void requireFinite(double x, const char* what) {
  if (!std::isfinite(x)) throw Error(cat("camera: ", what, " is not finite (", x, ")"));
}

void requireFinite(const glm::dvec3& v, const char* what) {
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
    throw Error(cat("camera: ", what, " (", v.x, ",", v.y, ",", v.z, ") is not finite"));
}

CameraFrame CameraFrame::fromDirection(const glm::dvec3& eye, const glm::dvec3& view,
                                       const glm::dvec3& up) {
  requireFinite(eye, "eye");
  requireFinite(view, "view direction");
  requireFinite(up, "up");
  const double viewLen = glm::length(view), upLen = glm::length(up);
  if (!(viewLen > 0)) throw Error("camera: the view direction is zero (eye == look-at point?)");
  if (!(upLen > 0)) throw Error("camera: the up vector is zero");
  CameraFrame f;
  f.e = eye;
  f.w = -view / viewLen;
  // Normalise up first so the parallel test is scale-free; |up × W| = sin(angle between them).
  const glm::dvec3 cross = glm::cross(up / upLen, f.w);
  const double s = glm::length(cross);
  if (!(s > 1e-15))
    throw Error(cat("camera: up (", up.x, ",", up.y, ",", up.z,
                    ") is parallel to the view direction (", view.x, ",", view.y, ",", view.z,
                    ")"));
  f.u = cross / s;
  // With up nearly parallel to W the cross product cancels: its rounding, relative to its
  // length s, leaves U off-perpendicular to W by ~1e-16 / s (2e-12 at 0.0001°). One
  // Gram-Schmidt pass against W restores it; then V = W × U, and a pass removes V's rounding,
  // so the frame is orthonormal to ~1 ulp at any angle the parallel test accepts.
  f.u = glm::normalize(f.u - glm::dot(f.u, f.w) * f.w);
  f.v = glm::cross(f.w, f.u);
  f.v = glm::normalize(f.v - glm::dot(f.v, f.u) * f.u);
  return f;
}

CameraFrame CameraFrame::fromLookAt(const glm::dvec3& eye, const glm::dvec3& at,
                                    const glm::dvec3& up) {
  requireFinite(at, "look-at point");
  if (eye == at)
    throw Error(
        cat("camera: the look-at point equals the eye (", eye.x, ",", eye.y, ",", eye.z, ")"));
  return fromDirection(eye, at - eye, up);
}

glm::dmat4 CameraFrame::cameraFromWorld() const { return standardCameraFromWorld(e, u, v, w); }

}  // namespace aperture
