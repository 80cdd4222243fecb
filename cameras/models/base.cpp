#include "cameras/models/base.h"

#include <cmath>
#include <optional>

#include "cameras/schema/conventions.h"
#include "core/util/error.h"
#include "core/util/sampling.h"
#include "core/util/units.h"

namespace aperture {

// The parameters CameraBase reads: the ones every model shares and those that place a planar
// image window. Each is declared once, here; its default and range are read from the
// declaration wherever they are applied (resolveImagePlane below, the command line's framing).

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

namespace {
double radians(double deg) { return deg * kPi / 180.0; }
}  // namespace

void resolveImagePlane(const CameraParams& p, double& d, double& vw, double& vh) {
  d = p.d.value_or(distanceParamSpec().defaultAs<double>());
  if (p.viewport) {
    vw = p.viewport->x;
    vh = p.viewport->y;
  } else if (p.focalLengthMm) {
    const glm::dvec2 v =
        viewportOfSensor(*p.focalLengthMm, p.sensorMm, p.sensorFit, p.width, p.height, d);
    vw = v.x;
    vh = v.y;
  } else {
    const glm::dvec2 v = viewportOfFov(p.fovDeg.value_or(fovParamSpec().defaultAs<double>()),
                                       p.fovAxis, p.width, p.height, d);
    vw = v.x;
    vh = v.y;
  }
  requireFinite(vw, "viewport width");
  requireFinite(vh, "viewport height");
  if (!(vw > 0 && vh > 0))
    throw Error(cat("camera: viewport ", vw, "x", vh, " must be > 0 in both directions"));
}

CameraFrame frameFromParams(const CameraParams& p) {
  if (p.at && p.dir)
    throw Error("camera: give either a look-at point or a view direction, not both");
  if (p.at) return CameraFrame::fromLookAt(p.eye, *p.at, p.up);
  if (p.dir) return CameraFrame::fromDirection(p.eye, *p.dir, p.up);
  return CameraFrame::fromLookAt(p.eye, glm::dvec3(0.0), p.up);
}

CameraBase::CameraBase(const CameraParams& p, const glm::dvec3& renderOrigin, const char* typeName)
    : CameraBase(p, frameFromParams(p), renderOrigin, typeName) {}

CameraBase::CameraBase(const CameraParams& p, const CameraFrame& frame,
                       const glm::dvec3& renderOrigin, const char* typeName)
    : params_(p), frame_(frame), renderOrigin_(renderOrigin), type_(typeName) {
  requireFinite(renderOrigin, "render origin");
  resolveImagePlane(p, d_, vw_, vh_);
  width_ = p.width;
  height_ = p.height;
  spp_ = p.spp;
  if (p.blenderShift && p.shift != glm::dvec2(0.0))
    throw Error("camera: give either a shift or a Blender shift, not both");
  shift_ =
      p.blenderShift ? shiftOfBlenderShift(*p.blenderShift, p.sensorFit, width_, height_) : p.shift;
  if (p.architectural) {
    // Keep the image plane parallel to up. With Y = normalize(up) and the requested view
    // direction D = −W0 = cos(t)·H + sin(t)·Y (H horizontal, t the tilt above the horizon),
    // the new frame looks along H (W = −H, U unchanged, V = Y). D's image-plane point
    // u·U + v·V − d·W ∝ D gives u = 0, v = d·tan(t): the tilt becomes the vertical shift
    //   sy += d·tan(t) / vh,
    // so the scene point on the requested axis stays at the image centre.
    const glm::dvec3 upUnit = glm::normalize(p.up);
    const glm::dvec3 view = -frame_.w;
    const double sinT = glm::dot(view, upUnit);
    const glm::dvec3 horizontal = view - sinT * upUnit;
    const double cosT = glm::length(horizontal);
    tiltRad_ = std::atan2(sinT, cosT);
    if (!(std::abs(tiltRad_) < radians(89.0)))
      throw Error(
          cat("camera: --architectural needs a view direction less than 89 degrees "
              "from the horizon (tilt is ",
              tiltRad_ * 180.0 / kPi, " degrees)"));
    frame_ = CameraFrame::fromDirection(frame_.e, horizontal, p.up);
    shift_.y += d_ * (sinT / cosT) / vh_;
  }
  renderEyeD_ = frame_.e - renderOrigin_;
  renderEye_ = glm::vec3(renderEyeD_);
  viewAxis_ = glm::vec3(-frame_.w);
}

void CameraBase::rejectShift() const {
  if (params_.shift != glm::dvec2(0.0) || params_.blenderShift || params_.architectural ||
      params_.clip)
    throw Error(
        cat("camera: --shift, --blender-shift, --architectural and --clip apply to perspective "
            "and thinlens cameras, not to '",
            type_, "'"));
}

namespace {
// A pseudo-random permutation of [0, n), chosen by `seed`: bijective steps on the next power
// of two (xor, odd multiply, xorshift, add), repeated until the value falls below n.
uint32_t permuteIndex(uint32_t index, uint32_t n, uint32_t seed) {
  uint32_t mask = n - 1;
  mask |= mask >> 1;
  mask |= mask >> 2;
  mask |= mask >> 4;
  mask |= mask >> 8;
  mask |= mask >> 16;
  const uint32_t salt = hash32(seed), mul = (hash32(seed + 1) | 1u);
  do {
    index = (index ^ salt) & mask;
    index = (index * mul) & mask;
    index ^= index >> 3;
    index = (index + (salt >> 16)) & mask;
    index ^= (index >> 1) & (salt >> 8) & mask;
  } while (index >= n);
  return index;
}
}  // namespace

void CameraBase::lensSample(int i, int j, int s, double& lensX, double& lensY) const {
  if (s == PacketRequest::kCentreRay) {
    lensX = lensY = 0.5;  // stratified2D's value at spp 1
    return;
  }
  const uint32_t seed = hash32(uint32_t(j) ^ hash32(uint32_t(i) ^ 0x5bd1e995u));
  const int stratum = spp_ > 1 ? int(permuteIndex(uint32_t(s), uint32_t(spp_), seed)) : s;
  stratified2D(uint32_t(j), uint32_t(i), stratum, spp_, 1, lensX, lensY);
}

void CameraBase::samplePosition(int i, int j, int s, double& x, double& y) const {
  double sx = 0.5, sy = 0.5;  // the centre: stratified2D's value at spp 1
  if (s != PacketRequest::kCentreRay) stratified2D(uint32_t(j), uint32_t(i), s, spp_, 0, sx, sy);
  x = j + sx;
  y = i + sy;
}

glm::dmat4 CameraBase::ndcFromPlane() const {
  glm::dmat4 m(1.0);  // GLM: m[column][row]
  m[0][0] = 1.0 / vw_;
  m[3][0] = -uLo() / vw_;
  m[1][1] = -1.0 / vh_;
  m[3][1] = vHi() / vh_;
  return m;
}

CameraDescription CameraBase::describe() const {
  CameraDescription c = describeWithoutCounts();
  describeCounts(c);
  return c;
}

CameraDescription CameraBase::describeWithoutCounts() const {
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
  if (const std::optional<glm::dmat4> plane = planeFromCamera())
    c.ndcFromWorld = ndcFromPlane() * *plane * c.cameraFromWorld;
  c.pixelAspectRatio = (vw_ / width_) / (vh_ / height_);
  c.extra.emplace_back("shift", cat(shift_.x, ",", shift_.y));
  if (params_.architectural) {
    c.extra.emplace_back("architectural", "1");
    c.extra.emplace_back("tilt_deg", cat(tiltRad_ * 180.0 / kPi));
  }
  describeExtra(c);
  return c;
}

}  // namespace aperture
