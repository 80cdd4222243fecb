#pragma once
// Converters from other renderers' camera conventions to aperture's own parameters
// (d, vw, vh, shift), and back to every convention for --describe. The table with the
// formulas is in docs/cameras.md.
#include <glm/glm.hpp>
#include <string>

#include "cameras/schema/param_schema.h"
#include "cameras/schema/params.h"

namespace aperture {

/// The full angles, in degrees, a planar image can span: (0, 180), where tan(fov / 2) is
/// finite and positive. The range of aperture's fov (declared with it in
/// cameras/models/base.cpp) and of the pbrt-v4 and Mitsuba 3 fov the converters below take.
inline constexpr ParamRange kPlanarFovRangeDeg = ParamRange::open(0.0, 180.0);

/// aperture's image plane: distance d and viewport vw x vh (scene units), shift in viewport
/// units.
struct ImagePlane {
  double d = 1, vw = 1, vh = 1;
  glm::dvec2 shift{0.0};
};

/// The viewport (vw, vh) at distance d of a full field of view fovDeg spanning `axis` of a
/// width x height image: vw or vh (or the diagonal) is 2·d·tan(fov/2), the other follows the
/// image's aspect ratio. The one fov-axis conversion (resolveImagePlane and the converters).
glm::dvec2 viewportOfFov(double fovDeg, FovAxis axis, int width, int height, double d);

/// pbrt-v4 `perspective`: "fov" (degrees) spans the shorter image axis.
ImagePlane fromPbrt(double fovDeg, int width, int height, double d = 1);

/// Mitsuba 3 `perspective`: "fov" (degrees) on "fov_axis" (default x).
enum class MitsubaFovAxis { X, Y, Diagonal, Smaller, Larger };
MitsubaFovAxis parseMitsubaFovAxis(const std::string& name);  ///< x|y|diagonal|smaller|larger
ImagePlane fromMitsuba(double fovDeg, MitsubaFovAxis axis, int width, int height, double d = 1);

/// Blender's sensor fit (Blender's BKE_camera_sensor_fit / BKE_camera_sensor_size): whether
/// the sensor spans the image width (Auto: when width >= height; Horizontal: always;
/// Vertical: never), and the sensor extent it spans (the width, the height for Vertical:
/// Auto uses the sensor width on the larger dimension whatever the sensor's aspect).
bool sensorFitsWidth(SensorFit fit, int width, int height);
double fittedSensorMm(SensorFit fit, const glm::dvec2& sensorMm);

/// The viewport (vw, vh) at distance d of focal length focalMm on a sensor of sensorMm
/// (width, height) under `fit`: the spanned image dimension gets d·fittedSensorMm / f, the
/// other follows the image's aspect ratio. The one sensor-fit conversion (resolveImagePlane
/// and fromBlender).
glm::dvec2 viewportOfSensor(double focalMm, const glm::dvec2& sensorMm, SensorFit fit, int width,
                            int height, double d);

/// Blender's lens shift (shift_x, shift_y: fractions of the image dimension the fit spans,
/// x right, y up; Blender moves the view plane by shift·that dimension) in viewport units.
glm::dvec2 shiftOfBlenderShift(const glm::dvec2& blenderShift, SensorFit fit, int width,
                               int height);

/// Blender: focal length and sensor size (mm) with sensor_fit and lens shift (see above).
/// Square pixels.
SensorFit parseBlenderSensorFit(const std::string& name);  ///< AUTO|HORIZONTAL|VERTICAL
ImagePlane fromBlender(double focalMm, double sensorWidthMm, double sensorHeightMm, SensorFit fit,
                       int width, int height, double d = 1,
                       const glm::dvec2& blenderShift = glm::dvec2(0.0));

/// OpenCV pinhole intrinsics (pixels): x = fx·X/Z + cx, y = fy·Y/Z + cy in a camera with
/// x right, y down, z forward, pixel centres at integer coordinates. aperture's raster
/// position is (x + ½, y + ½) and its V points up, so vw = d·W/fx, vh = d·H/fy,
/// sx = ½ − (cx + ½)/W, sy = (cy + ½)/H − ½. Skew and distortion are not supported.
ImagePlane fromOpenCV(double fx, double fy, double cx, double cy, int width, int height,
                      double d = 1);

/// Sets d, viewport and shift of `p` from `plane` (overriding fov and focal length).
void applyImagePlane(const ImagePlane& plane, CameraParams& p);

/// One perspective image plane expressed in every convention.
struct ConventionSummary {
  double fovXDeg = 0, fovYDeg = 0, fovDiagonalDeg = 0;  ///< full angles of the centred window
  double pbrtFovDeg = 0;                                ///< pbrt-v4 fov (shorter axis)
  double mitsubaFovXDeg = 0;              ///< Mitsuba fov with fov_axis x (the default)
  double focal35DiagonalMm = 0;           ///< 35 mm equivalent: same diagonal angle as 36 x 24 mm
  double focal35HorizontalMm = 0;         ///< 35 mm equivalent: same horizontal angle as 36 mm
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< OpenCV intrinsics, pixels
};
ConventionSummary toConventions(const ImagePlane& plane, int width, int height);

}  // namespace aperture
