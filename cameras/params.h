#pragma once
// Camera parameters as the user gives them (command line, job file). The lecture's own
// parameters (e, U, V, W, d, vw, vh) are the ground truth; the other conventions are
// converted into them by resolveImagePlane().
#include <glm/glm.hpp>
#include <optional>
#include <string>

namespace aperture {

enum class FovAxis { X, Y, Diagonal };

struct CameraParams {
  std::string type = "perspective";  ///< perspective orthographic oblique thinlens equirect fisheye
  int width = 640, height = 480;     ///< image size, pixels
  int spp = 1;                       ///< samples per pixel; 1 = pixel centres exactly

  // Frame (world space, scene units). Exactly one of `at` and `dir` is set.
  glm::dvec3 eye{0.0, 0.0, 5.0};
  std::optional<glm::dvec3> at;   ///< look-at point
  std::optional<glm::dvec3> dir;  ///< view direction (any length > 0)
  glm::dvec3 up{0.0, 1.0, 0.0};

  // Image plane. Priority: explicit d + viewport; else focal length + sensor; else fov.
  std::optional<double> d;              ///< image-plane distance, scene units (> 0)
  std::optional<glm::dvec2> viewport;   ///< vw, vh on the image plane, scene units (> 0)
  std::optional<double> fovDeg;         ///< field of view, degrees, in (0, 180)
  FovAxis fovAxis = FovAxis::Y;         ///< which extent fovDeg spans
  std::optional<double> focalLengthMm;  ///< 35 mm style focal length, millimetres
  glm::dvec2 sensorMm{36.0, 24.0};      ///< sensor width, height, millimetres

  // Shifted perspective.
  glm::dvec2 shift{0.0, 0.0};  ///< image-window offset in viewport units (0.5 = half a viewport)
  bool architectural = false;  ///< keep the image plane parallel to up; tilt becomes shift

  // Oblique parallel: one of these (direction in world space, or shear angles in degrees).
  std::optional<glm::dvec3> obliqueDir;
  std::optional<glm::dvec2> obliqueAnglesDeg;

  // Thin lens.
  double apertureRadius = 0.0;  ///< lens radius, scene units (0 = pinhole)
  double focusDistance = 1.0;   ///< distance of the in-focus plane along −W, scene units

  // Panoramas.
  glm::dvec2 longitudeRangeDeg{-180.0, 180.0};  ///< equirect horizontal extent, degrees
  glm::dvec2 latitudeRangeDeg{-90.0, 90.0};     ///< equirect vertical extent, degrees
  double fisheyeFovDeg = 180.0;                 ///< fisheye full field of view, (0, 360]
};

}  // namespace aperture
