// The parameters CameraBase reads (base.cpp): the ones every model shares and those that
// place a planar image window. Each is declared once, here; its default and range are read
// from the declaration wherever they are applied.
#include <optional>

#include "cameras/base.h"
#include "cameras/conventions.h"

namespace aperture {

namespace {

using K = ParamKind;

ParamAccess sizeAccess() {
  return {[](const CameraParams& p) -> std::optional<ParamValue> {
            return ParamValue(glm::ivec2(p.width, p.height));
          },
          [](CameraParams& p, const ParamValue& v) {
            const glm::ivec2 s = std::get<glm::ivec2>(v);
            p.width = s.x;
            p.height = s.y;
          }};
}

ParamAccess fovAxisAccess() {
  return {[](const CameraParams& p) -> std::optional<ParamValue> {
            return ParamValue(std::string(p.fovAxis == FovAxis::X   ? "x"
                                          : p.fovAxis == FovAxis::Y ? "y"
                                                                    : "diagonal"));
          },
          [](CameraParams& p, const ParamValue& v) {
            const std::string& a = std::get<std::string>(v);
            p.fovAxis = a == "x" ? FovAxis::X : a == "y" ? FovAxis::Y : FovAxis::Diagonal;
          }};
}

ParamAccess sensorFitAccess() {
  return {[](const CameraParams& p) -> std::optional<ParamValue> {
            return ParamValue(std::string(p.sensorFit == SensorFit::Auto         ? "auto"
                                          : p.sensorFit == SensorFit::Horizontal ? "horizontal"
                                                                                 : "vertical"));
          },
          [](CameraParams& p, const ParamValue& v) {
            const std::string& f = std::get<std::string>(v);
            p.sensorFit = f == "auto"         ? SensorFit::Auto
                          : f == "horizontal" ? SensorFit::Horizontal
                                              : SensorFit::Vertical;
          }};
}

const ParamSpec kType = ParamSpec("type", K::Choice, fieldAccess<&CameraParams::type>())
                            .withHelp("Camera model")
                            .withFlag("--camera");
const ParamSpec kSize = ParamSpec("size", K::Size, sizeAccess())
                            .withUnit("pixels")
                            .withHelp("Image size W,H (or WxH), at most 2^28 pixels")
                            .withRange(ParamRange::closed(1.0, 65536.0))
                            .withMaxPixels(double(1 << 28));
const ParamSpec kSpp = ParamSpec("spp", K::Integer, fieldAccess<&CameraParams::spp>())
                           .withHelp("Samples per pixel (stratified; 1 = pixel centres)")
                           .withRange(ParamRange::closed(1.0, 65536.0));
const ParamSpec kEye =
    ParamSpec("eye", K::Vec3, fieldAccess<&CameraParams::eye>())
        .withUnit("scene units")
        .withHelp("Eye position e")
        .withDefaultRule(
            "render, bench: frames the scene; job files: required unless a path (orbit, "
            "keyframes) sets it");
const ParamSpec kAt =
    ParamSpec("at", K::Vec3, fieldAccess<&CameraParams::at>())
        .withUnit("scene units")
        .withHelp("Look-at point")
        .withDefaultRule("the scene's centre (render, bench; the origin for `camera`)")
        .withConflicts({"dir"});
const ParamSpec kDir = ParamSpec("dir", K::Vec3, fieldAccess<&CameraParams::dir>())
                           .withHelp("View direction (any length)")
                           .withConflicts({"at"});
const ParamSpec kUp = ParamSpec("up", K::Vec3, fieldAccess<&CameraParams::up>())
                          .withHelp("Up vector (any length, not parallel to the view)");

const ParamSpec kD = ParamSpec("d", K::Number, fieldAccess<&CameraParams::d>())
                         .withUnit("scene units")
                         .withHelp("Image-plane distance d (with viewport)")
                         .withDefault(1.0, "{} when viewport is given")
                         .withRange(ParamRange::above(0.0))
                         .withNeeds({"viewport"});
const ParamSpec kViewport =
    ParamSpec("viewport", K::Vec2, fieldAccess<&CameraParams::viewport>())
        .withUnit("scene units")
        .withHelp("Viewport VW,VH on the image plane")
        .withDefaultRule("none (perspective: from fov; parallel cameras need it)")
        .withRange(ParamRange::above(0.0))
        .withConflicts({"fov", "focal_length"});

const ParamSpec kFov = ParamSpec("fov", K::Number, fieldAccess<&CameraParams::fovDeg>())
                           .withUnit("degrees")
                           .withHelp("Field of view")
                           .withDefault(45.0,
                                        "{} vertical, when neither viewport nor focal_length "
                                        "is given")
                           .withRange(kPlanarFovRangeDeg)
                           .withConflicts({"focal_length", "viewport"});
const ParamSpec kFovAxis = ParamSpec("fov_axis", K::Choice, fovAxisAccess())
                               .withHelp("The extent fov spans")
                               .withChoices({"x", "y", "diagonal"});
const ParamSpec kFocalLength =
    ParamSpec("focal_length", K::Number, fieldAccess<&CameraParams::focalLengthMm>())
        .withUnit("mm")
        .withHelp("35 mm-style focal length")
        .withRange(ParamRange::above(0.0))
        .withConflicts({"fov", "viewport"});
const ParamSpec kSensor =
    ParamSpec("sensor", K::Vec2, fieldAccess<&CameraParams::sensorMm>())
        .withUnit("mm")
        .withHelp("Sensor W,H for focal_length (sensor_fit says which image side it spans)")
        .withRange(ParamRange::above(0.0))
        .withNeeds({"focal_length"});
const ParamSpec kSensorFit =
    ParamSpec("sensor_fit", K::Choice, sensorFitAccess())
        .withHelp(
            "Image side the sensor spans, as Blender: auto = sensor width on the larger side, "
            "horizontal = width on the width, vertical = height on the height")
        .withChoices({"auto", "horizontal", "vertical"})
        .withNeeds({"focal_length"});
const ParamSpec kShift = ParamSpec("shift", K::Vec2, fieldAccess<&CameraParams::shift>())
                             .withUnit("viewports")
                             .withHelp("Lens shift SX,SY (0.5 = half a viewport)")
                             .withConflicts({"blender_shift"});
const ParamSpec kBlenderShift =
    ParamSpec("blender_shift", K::Vec2, fieldAccess<&CameraParams::blenderShift>())
        .withUnit("fitted sides")
        .withHelp(
            "Blender's lens shift shift_x,shift_y: fractions of the image side the sensor fit "
            "spans (the larger one for auto)")
        .withDefaultRule("none")
        .withConflicts({"shift"});
const ParamSpec kArchitectural =
    ParamSpec("architectural", K::Flag, fieldAccess<&CameraParams::architectural>())
        .withHelp(
            "Keep the image plane parallel to up (verticals stay parallel; the tilt becomes a "
            "shift)");

}  // namespace

const std::vector<const ParamSpec*>& commonParamSpecs() {
  static const std::vector<const ParamSpec*> v = {&kType, &kSize, &kSpp, &kEye, &kAt, &kDir, &kUp};
  return v;
}
const ParamSpec& distanceParamSpec() { return kD; }
const ParamSpec& viewportParamSpec() { return kViewport; }
const ParamSpec& fovParamSpec() { return kFov; }

const std::vector<const ParamSpec*>& perspectiveWindowParamSpecs() {
  static const std::vector<const ParamSpec*> v = {&kFov,          &kFovAxis,      &kFocalLength,
                                                  &kSensor,       &kSensorFit,    &kShift,
                                                  &kBlenderShift, &kArchitectural};
  return v;
}

std::vector<const ParamSpec*> joinParamSpecs(
    std::initializer_list<std::vector<const ParamSpec*>> groups) {
  std::vector<const ParamSpec*> all;
  for (const auto& g : groups) all.insert(all.end(), g.begin(), g.end());
  return all;
}

}  // namespace aperture
