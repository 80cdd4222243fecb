#pragma once
// The camera frame (e, U, V, W) of the lecture, in double precision.
#include <glm/glm.hpp>

namespace aperture {

/// Orthonormal right-handed frame: U right, V up, W backwards (away from the view direction).
struct CameraFrame {
  glm::dvec3 e{0.0};  ///< eye, world space
  glm::dvec3 u{1.0, 0.0, 0.0};
  glm::dvec3 v{0.0, 1.0, 0.0};
  glm::dvec3 w{0.0, 0.0, 1.0};

  /// W = −normalize(view), U = normalize(up × W), V = W × U. Throws Error when a vector is zero
  /// or non-finite, or `up` is parallel to `view` (|up × W| below 1e-300 relative).
  static CameraFrame fromDirection(const glm::dvec3& eye, const glm::dvec3& view,
                                   const glm::dvec3& up);
  /// The same with view = at − eye (error if at == eye).
  static CameraFrame fromLookAt(const glm::dvec3& eye, const glm::dvec3& at, const glm::dvec3& up);

  /// OpenEXR's camera space from world (left-handed: x = U, y = V, z = −W, the viewing
  /// direction), column-vector convention; standardCameraFromWorld() of core/engine/camera.h.
  glm::dmat4 cameraFromWorld() const;
};

/// Throws Error naming `what` if any component of v is NaN or infinite.
void requireFinite(const glm::dvec3& v, const char* what);
void requireFinite(double x, const char* what);

}  // namespace aperture
