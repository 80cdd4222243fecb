#include "cameras/models/base.h"

#include <cmath>

#include "cameras/models/calibrated.h"
#include "cameras/models/models.h"
#include "cameras/schema/conventions.h"
#include "core/util/error.h"
#include "core/util/sampling.h"
#include "core/util/units.h"

namespace aperture {

namespace {
double radians(double deg) { return deg * kPi / 180.0; }
}  // namespace

namespace {

using K = ParamKind;
const ParamRange kPositive{0.0, std::nullopt, true, false};

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

const ParamSpec kType{"type",    K::Choice,
                      "",        "Camera model",
                      nullptr,   {},
                      {},        {},
                      {},        fieldAccess<&CameraParams::type>(),
                      "--camera"};
const ParamSpec kSize{
    "size",  K::Size,        "pixels", "Image size W,H (or WxH), at most 2^28 pixels",
    nullptr, {1.0, 65536.0}, {},       {},
    {},      sizeAccess()};
const ParamSpec kSpp{"spp",   K::Integer,
                     "",      "Samples per pixel (stratified; 1 = pixel centres)",
                     nullptr, {1.0, 65536.0},
                     {},      {},
                     {},      fieldAccess<&CameraParams::spp>()};
const ParamSpec kEye{"eye",
                     K::Vec3,
                     "scene units",
                     "Eye position e",
                     "render, bench: frames the scene; job files: required unless a path "
                     "(orbit, keyframes) sets it",
                     {},
                     {},
                     {},
                     {},
                     fieldAccess<&CameraParams::eye>()};
const ParamSpec kAt{"at",
                    K::Vec3,
                    "scene units",
                    "Look-at point",
                    "the scene's centre (render, bench; the origin for `camera`)",
                    {},
                    {},
                    {"dir"},
                    {},
                    fieldAccess<&CameraParams::at>()};
const ParamSpec kDir{"dir", K::Vec3, "", "View direction (any length)",    nullptr, {},
                     {},    {"at"},  {}, fieldAccess<&CameraParams::dir>()};
const ParamSpec kUp{"up",    K::Vec3,
                    "",      "Up vector (any length, not parallel to the view)",
                    nullptr, {},
                    {},      {},
                    {},      fieldAccess<&CameraParams::up>()};
const ParamSpec kD{"d",
                   K::Number,
                   "scene units",
                   "Image-plane distance d (with viewport)",
                   "1 when viewport is given",
                   kPositive,
                   {},
                   {},
                   {"viewport"},
                   fieldAccess<&CameraParams::d>()};
const ParamSpec kViewport{"viewport",
                          K::Vec2,
                          "scene units",
                          "Viewport VW,VH on the image plane",
                          "none (perspective: from fov; parallel cameras need it)",
                          kPositive,
                          {},
                          {"fov", "focal_length"},
                          {},
                          fieldAccess<&CameraParams::viewport>()};

}  // namespace

const std::vector<const ParamSpec*>& commonParamSpecs() {
  static const std::vector<const ParamSpec*> v = {&kType, &kSize, &kSpp, &kEye, &kAt, &kDir, &kUp};
  return v;
}
const ParamSpec& distanceParamSpec() { return kD; }
const ParamSpec& viewportParamSpec() { return kViewport; }

std::vector<const ParamSpec*> joinParamSpecs(
    std::initializer_list<std::vector<const ParamSpec*>> groups) {
  std::vector<const ParamSpec*> all;
  for (const auto& g : groups) all.insert(all.end(), g.begin(), g.end());
  return all;
}

double focusDistanceOf(const CameraParams& p) {
  if (p.focusDistance) return *p.focusDistance;
  return p.at ? glm::length(*p.at - p.eye) : 1.0;
}

void resolveImagePlane(const CameraParams& p, double& d, double& vw, double& vh) {
  d = p.d.value_or(1.0);
  if (p.viewport) {
    vw = p.viewport->x;
    vh = p.viewport->y;
  } else if (p.focalLengthMm) {
    const glm::dvec2 v =
        viewportOfSensor(*p.focalLengthMm, p.sensorMm, p.sensorFit, p.width, p.height, d);
    vw = v.x;
    vh = v.y;
  } else {
    const glm::dvec2 v =
        viewportOfFov(p.fovDeg.value_or(kDefaultFovDeg), p.fovAxis, p.width, p.height, d);
    vw = v.x;
    vh = v.y;
  }
  requireFinite(vw, "viewport width");
  requireFinite(vh, "viewport height");
  if (!(vw > 0 && vh > 0))
    throw Error(cat("camera: viewport ", vw, "x", vh, " must be > 0 in both directions"));
}

CameraFrame frameFromParams(const CameraParams& p) {
  if (p.worldToCamera || p.cameraToWorld) return frameOfWorldToCamera(calibratedWorldToCamera(p));
  if (p.at && p.dir)
    throw Error("camera: give either a look-at point or a view direction, not both");
  if (p.at) return CameraFrame::fromLookAt(p.eye, *p.at, p.up);
  if (p.dir) return CameraFrame::fromDirection(p.eye, *p.dir, p.up);
  return CameraFrame::fromLookAt(p.eye, glm::dvec3(0.0), p.up);
}

CameraBase::CameraBase(const CameraParams& p, const glm::dvec3& renderOrigin, const char* typeName)
    : params_(p), renderOrigin_(renderOrigin), type_(typeName) {
  requireFinite(renderOrigin, "render origin");
  frame_ = frameFromParams(p);
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
