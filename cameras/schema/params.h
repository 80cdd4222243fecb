#pragma once
// Camera parameters, resolved: what a camera model is built from. The lecture's own parameters
// (e, U, V, W, d, vw, vh) are the ground truth; the other conventions are converted into them
// by resolveImagePlane(). Every field is declared for users once, in the parameter schema
// (cameras/schema/param_schema.h): its name, unit, default, range, conflicts and help. Front ends
// (command line, job files, Python) fill a ParamSet and resolve it into this struct; a field
// the user need not give is std::optional when "not given" means something else than a value.
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

namespace aperture {

enum class FovAxis { X, Y, Diagonal };

/// Which image dimension the sensor spans (Blender's sensor_fit): Auto the larger one (the
/// width of a square image) with the sensor width, Horizontal the width with the sensor width,
/// Vertical the height with the sensor height. Resolved by sensorFitsWidth() and
/// viewportOfSensor() (cameras/schema/conventions.h).
enum class SensorFit { Auto, Horizontal, Vertical };

struct CameraParams {
  std::string type = "perspective";  ///< a registered model: see cameraTypeNames()
  int width = 960, height = 540;     ///< image size, pixels
  int spp = 1;                       ///< samples per pixel; 1 = pixel centres exactly

  // Frame (world space, scene units). At most one of `at` and `dir` is set; with neither the
  // camera looks at the world origin.
  glm::dvec3 eye{0.0, 0.0, 5.0};
  std::optional<glm::dvec3> at;   ///< look-at point
  std::optional<glm::dvec3> dir;  ///< view direction (any length > 0)
  glm::dvec3 up{0.0, 1.0, 0.0};

  // Image plane. At most one of: viewport (with d), focal length (with sensor and sensorFit),
  // fov (on fovAxis); with none, fov's default. The defaults and ranges of d and fov are their
  // specs' (cameras/models/base.cpp).
  std::optional<double> d;                ///< image-plane distance, scene units
  std::optional<glm::dvec2> viewport;     ///< vw, vh on the image plane, scene units
  std::optional<double> fovDeg;           ///< field of view, degrees
  FovAxis fovAxis = FovAxis::Y;           ///< which extent fovDeg spans
  std::optional<double> focalLengthMm;    ///< 35 mm style focal length, millimetres
  glm::dvec2 sensorMm{36.0, 24.0};        ///< sensor width, height, millimetres
  SensorFit sensorFit = SensorFit::Auto;  ///< how the sensor fits the image (focal length)

  // Shifted perspective.
  glm::dvec2 shift{0.0, 0.0};  ///< image-window offset in viewport units (0.5 = half a viewport)
  /// Blender's lens shift (shift_x, shift_y) instead of `shift`: fractions of the image
  /// dimension the sensor fit spans (the larger one for SensorFit::Auto), x right, y up.
  std::optional<glm::dvec2> blenderShift;
  bool architectural = false;  ///< keep the image plane parallel to up; tilt becomes shift

  /// Clipping (perspective and thin lens): near and far planar depth along the view axis,
  /// scene units, as Blender's clip_start and clip_end; not set: no clipping (see
  /// core/engine/camera.h for the rays' tnear and tfar).
  std::optional<glm::dvec2> clip;

  // Oblique parallel: one of these (direction in world space, or shear angles in degrees).
  std::optional<glm::dvec3> obliqueDir;
  std::optional<glm::dvec2> obliqueAnglesDeg;

  // Thin lens.
  double apertureRadius = 0.0;  ///< lens radius, scene units (0 = pinhole)
  /// Distance of the in-focus plane along −W, scene units; not given: see focusDistanceOf()
  /// (cameras/models/thinlens.h).
  std::optional<double> focusDistance;

  // Panoramas.
  glm::dvec2 longitudeRangeDeg{-180.0, 180.0};  ///< equirect horizontal extent, degrees
  glm::dvec2 latitudeRangeDeg{-90.0, 90.0};     ///< equirect vertical extent, degrees
  double fisheyeFovDeg = 180.0;                 ///< fisheye full field of view

  // Calibrated (cameras/models/calibrated.cpp): a lens in a source's conventions and, instead of
  // eye / at / up, optionally a pose matrix (16 numbers, row-major).
  std::optional<std::vector<double>> intrinsics;  ///< fx, fy, cx, cy, pixels
  std::string lensModel = "PINHOLE";  ///< a COLMAP model name (cameras/lenses/lens_model.h)
  std::optional<std::vector<double>> distortion;  ///< the model's coefficients, COLMAP's order
  std::string pixelCentre = "half-integer";       ///< "half-integer" (COLMAP) or "integer" (OpenCV)
  std::optional<std::vector<double>> worldToCamera;
  std::optional<std::vector<double>> cameraToWorld;
  std::string convention = "opencv";  ///< axes of the pose matrix: opencv, opengl, blender
};

}  // namespace aperture
