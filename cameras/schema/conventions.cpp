#include "cameras/schema/conventions.h"

#include <cctype>
#include <cmath>

#include "cameras/schema/image_window.h"
#include "core/util/error.h"
#include "core/util/spelling.h"
#include "core/util/units.h"

namespace aperture {

namespace {

void checkImage(int width, int height, double d) {
  if (width <= 0 || height <= 0)
    throw Error(cat("conventions: image size ", width, "x", height, " must be positive"));
  if (!(d > 0 && std::isfinite(d))) throw Error(cat("conventions: d = ", d, " must be > 0"));
}

void checkFov(double fovDeg) {
  if (!kPlanarFovRangeDeg.contains(fovDeg))
    throw Error(
        cat("conventions: fov ", fovDeg, " degrees must be in ", kPlanarFovRangeDeg.text()));
}

double fullAngleDeg(double extent, double d) {
  return 2.0 * std::atan(0.5 * extent / d) / kRadPerDeg;
}

}  // namespace

glm::dvec2 viewportOfFov(double fovDeg, FovAxis axis, int width, int height, double d) {
  const double extent = 2.0 * d * std::tan(fovDeg * kPi / 180.0 / 2.0);
  const double aspect = double(width) / double(height);
  switch (axis) {
    case FovAxis::X:
      return {extent, extent / aspect};
    case FovAxis::Y:
      return {extent * aspect, extent};
    case FovAxis::Diagonal:
      break;
  }
  const double diag = std::hypot(double(width), double(height));
  return {extent * width / diag, extent * height / diag};
}

ImagePlane fromPbrt(double fovDeg, int width, int height, double d) {
  checkImage(width, height, d);
  checkFov(fovDeg);
  const glm::dvec2 v =
      viewportOfFov(fovDeg, width >= height ? FovAxis::Y : FovAxis::X, width, height, d);
  return {d, v.x, v.y, glm::dvec2(0.0)};
}

MitsubaFovAxis parseMitsubaFovAxis(const std::string& name) {
  const std::string n = toLowerAscii(name);
  if (n == "x") return MitsubaFovAxis::X;
  if (n == "y") return MitsubaFovAxis::Y;
  if (n == "diagonal") return MitsubaFovAxis::Diagonal;
  if (n == "smaller") return MitsubaFovAxis::Smaller;
  if (n == "larger") return MitsubaFovAxis::Larger;
  throw Error(
      cat("unknown Mitsuba fov_axis '", name, "' (known: x, y, diagonal, smaller, larger)"));
}

ImagePlane fromMitsuba(double fovDeg, MitsubaFovAxis axis, int width, int height, double d) {
  checkImage(width, height, d);
  checkFov(fovDeg);
  if (axis == MitsubaFovAxis::Smaller)
    axis = width <= height ? MitsubaFovAxis::X : MitsubaFovAxis::Y;
  if (axis == MitsubaFovAxis::Larger)
    axis = width >= height ? MitsubaFovAxis::X : MitsubaFovAxis::Y;
  const FovAxis a = axis == MitsubaFovAxis::X   ? FovAxis::X
                    : axis == MitsubaFovAxis::Y ? FovAxis::Y
                                                : FovAxis::Diagonal;
  const glm::dvec2 v = viewportOfFov(fovDeg, a, width, height, d);
  return {d, v.x, v.y, glm::dvec2(0.0)};
}

bool sensorFitsWidth(SensorFit fit, int width, int height) {
  switch (fit) {
    case SensorFit::Horizontal:
      return true;
    case SensorFit::Vertical:
      return false;
    case SensorFit::Auto:
      break;
  }
  return width >= height;
}

double fittedSensorMm(SensorFit fit, const glm::dvec2& sensorMm) {
  return fit == SensorFit::Vertical ? sensorMm.y : sensorMm.x;
}

glm::dvec2 viewportOfSensor(double focalMm, const glm::dvec2& sensorMm, SensorFit fit, int width,
                            int height, double d) {
  const double extent = d * fittedSensorMm(fit, sensorMm) / focalMm;
  const double aspect = double(width) / double(height);
  if (sensorFitsWidth(fit, width, height)) return {extent, extent / aspect};
  return {extent * aspect, extent};
}

glm::dvec2 shiftOfBlenderShift(const glm::dvec2& blenderShift, SensorFit fit, int width,
                               int height) {
  const double spanned = sensorFitsWidth(fit, width, height) ? width : height;
  return ImageWindow::shiftForPixelOffset(blenderShift.x * spanned, blenderShift.y * spanned, width,
                                          height);
}

SensorFit parseBlenderSensorFit(const std::string& name) {
  const std::string n = toLowerAscii(name);
  if (n == "auto") return SensorFit::Auto;
  if (n == "horizontal") return SensorFit::Horizontal;
  if (n == "vertical") return SensorFit::Vertical;
  throw Error(cat("unknown Blender sensor_fit '", name, "' (known: AUTO, HORIZONTAL, VERTICAL)",
                  didYouMean(name, {"AUTO", "HORIZONTAL", "VERTICAL"})));
}

ImagePlane fromBlender(double focalMm, double sensorWidthMm, double sensorHeightMm, SensorFit fit,
                       int width, int height, double d, const glm::dvec2& blenderShift) {
  checkImage(width, height, d);
  if (!(focalMm > 0 && sensorWidthMm > 0 && sensorHeightMm > 0 && std::isfinite(focalMm) &&
        std::isfinite(sensorWidthMm) && std::isfinite(sensorHeightMm)))
    throw Error(cat("conventions: focal length ", focalMm, " mm and sensor ", sensorWidthMm, "x",
                    sensorHeightMm, " mm must be positive"));
  if (!(std::isfinite(blenderShift.x) && std::isfinite(blenderShift.y)))
    throw Error(
        cat("conventions: Blender shift ", blenderShift.x, ",", blenderShift.y, " must be finite"));
  const glm::dvec2 v =
      viewportOfSensor(focalMm, {sensorWidthMm, sensorHeightMm}, fit, width, height, d);
  return {d, v.x, v.y, shiftOfBlenderShift(blenderShift, fit, width, height)};
}

ImagePlane fromOpenCV(double fx, double fy, double cx, double cy, int width, int height, double d) {
  checkImage(width, height, d);
  if (!(fx > 0 && fy > 0 && std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) &&
        std::isfinite(cy)))
    throw Error(cat("conventions: OpenCV intrinsics fx ", fx, ", fy ", fy, ", cx ", cx, ", cy ", cy,
                    " must be finite with fx, fy > 0"));
  ImagePlane p;
  p.d = d;
  p.vw = d * width / fx;
  p.vh = d * height / fy;
  // OpenCV puts pixel centres at integers, aperture's raster at half-integers.
  p.shift = ImageWindow::shiftForPrincipalPoint(cx + 0.5, cy + 0.5, width, height);
  return p;
}

void applyImagePlane(const ImagePlane& plane, CameraParams& p) {
  p.d = plane.d;
  p.viewport = glm::dvec2(plane.vw, plane.vh);
  p.shift = plane.shift;
  p.fovDeg.reset();
  p.focalLengthMm.reset();
}

ConventionSummary toConventions(const ImagePlane& plane, int width, int height) {
  checkImage(width, height, plane.d);
  ConventionSummary s;
  const double d = plane.d;
  s.fovXDeg = fullAngleDeg(plane.vw, d);
  s.fovYDeg = fullAngleDeg(plane.vh, d);
  s.fovDiagonalDeg = fullAngleDeg(std::hypot(plane.vw, plane.vh), d);
  s.pbrtFovDeg = width >= height ? s.fovYDeg : s.fovXDeg;
  s.mitsubaFovXDeg = s.fovXDeg;
  s.focal35DiagonalMm = std::hypot(36.0, 24.0) * d / std::hypot(plane.vw, plane.vh);
  s.focal35HorizontalMm = 36.0 * d / plane.vw;
  s.fx = d * width / plane.vw;
  s.fy = d * height / plane.vh;
  const glm::dvec2 principal =
      ImageWindow{width, height, plane.vw, plane.vh, plane.shift}.principalPoint();
  s.cx = principal.x - 0.5;
  s.cy = principal.y - 0.5;
  return s;
}

}  // namespace aperture
