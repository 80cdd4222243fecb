#include "apps/jobs/camera_paths.h"

#include <cmath>

#include "core/util/units.h"

namespace aperture::app {

OrbitPath parseOrbit(const Object& c, const CameraParams& base) {
  const Object o(c.file(), c.keyPath("orbit"), c.required("orbit"),
                 {"centre", "radius", "height", "elevation", "start", "sweep"});
  OrbitPath orbit;
  orbit.centre = o.vec3("centre").value_or(glm::dvec3(0.0));
  if (!o.has("radius")) o.fail(o.keyPath("radius"), "required key is missing");
  orbit.radius = *o.number("radius");
  if (!(orbit.radius > 0)) o.fail(o.keyPath("radius"), cat(orbit.radius, ": must be > 0"));
  orbit.height = o.number("height");
  orbit.elevationDeg = o.number("elevation");
  if (orbit.height && orbit.elevationDeg) o.fail(o.path(), "give height or elevation, not both");
  if (orbit.elevationDeg && !(std::abs(*orbit.elevationDeg) < 90))
    o.fail(o.keyPath("elevation"), cat(*orbit.elevationDeg, ": must be in (-90, 90) degrees"));
  orbit.startDeg = o.number("start", 0.0);
  orbit.sweepDeg = o.number("sweep", 360.0);
  orbit.up = base.up;
  if (glm::length(orbit.up) < 1e-12) c.fail(c.keyPath("up"), "up has zero length");
  return orbit;
}

std::vector<Keyframe> parseKeyframes(const Object& c, const CameraParams& base) {
  const json& list = c.array("keyframes");
  const std::string where = c.keyPath("keyframes");
  if (list.empty()) c.fail(where, "needs at least one keyframe");
  std::vector<Keyframe> keys;
  size_t withFov = 0;
  for (size_t k = 0; k < list.size(); ++k) {
    const Object e(c.file(), indexPath(where, k), list[k], {"frame", "eye", "at", "up", "fov"});
    Keyframe key;
    if (!e.has("frame")) e.fail(e.keyPath("frame"), "required key is missing");
    key.frame = *e.integer("frame");
    if (key.frame < 0) e.fail(e.keyPath("frame"), cat(key.frame, ": must be >= 0"));
    if (!keys.empty() && key.frame <= keys.back().frame)
      e.fail(e.keyPath("frame"), cat(key.frame, ": keyframes must ascend strictly by frame"));
    if (!e.has("eye")) e.fail(e.keyPath("eye"), "required key is missing");
    if (!e.has("at")) e.fail(e.keyPath("at"), "required key is missing");
    key.eye = *e.vec3("eye");
    key.at = *e.vec3("at");
    key.up = e.vec3("up").value_or(base.up);
    key.fovDeg = e.number("fov");
    if (!key.fovDeg) key.fovDeg = base.fovDeg;
    if (key.fovDeg) ++withFov;
    keys.push_back(key);
  }
  if (withFov != 0 && withFov != keys.size())
    c.fail(where, "either every keyframe has a fov (or the camera gives one) or none has");
  return keys;
}

glm::dvec3 orbitEye(const OrbitPath& orbit, int k) {
  const glm::dvec3 a = glm::normalize(orbit.up);
  glm::dvec3 ref(0, 0, 1);
  if (std::abs(glm::dot(ref, a)) > 0.999) ref = glm::dvec3(1, 0, 0);
  const glm::dvec3 e1 = glm::normalize(ref - glm::dot(ref, a) * a);
  const glm::dvec3 e2 = glm::cross(a, e1);
  const double theta =
      (orbit.startDeg + orbit.sweepDeg * double(k) / double(orbit.frames)) * kPi / 180.0;
  const glm::dvec3 around = std::cos(theta) * e1 + std::sin(theta) * e2;
  if (orbit.elevationDeg) {
    const double phi = *orbit.elevationDeg * kPi / 180.0;
    return orbit.centre + orbit.radius * (std::cos(phi) * around + std::sin(phi) * a);
  }
  return orbit.centre + orbit.radius * around + orbit.height.value_or(0.0) * a;
}

Keyframe interpolateKeyframes(const std::vector<Keyframe>& keys, int f) {
  if (f <= keys.front().frame) {
    Keyframe k = keys.front();
    k.frame = f;
    return k;
  }
  for (size_t i = 0; i + 1 < keys.size(); ++i) {
    const Keyframe& a = keys[i];
    const Keyframe& b = keys[i + 1];
    if (f > b.frame) continue;
    const double t = double(f - a.frame) / double(b.frame - a.frame);
    Keyframe k;
    k.frame = f;
    k.eye = (1 - t) * a.eye + t * b.eye;
    k.at = (1 - t) * a.at + t * b.at;
    k.up = (1 - t) * a.up + t * b.up;
    if (a.fovDeg && b.fovDeg) k.fovDeg = (1 - t) * *a.fovDeg + t * *b.fovDeg;
    return k;
  }
  Keyframe k = keys.back();
  k.frame = f;
  return k;
}

}  // namespace aperture::app
