#include "apps/jobs/job_camera.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>

#include "apps/jobs/camera_paths.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/conventions.h"
#include "core/util/spelling.h"
#include "core/util/units.h"

namespace aperture::app {

namespace {

bool validName(const std::string& name) {
  if (name.empty() || name.size() > 128 || name == "." || name == "..") return false;
  return std::all_of(name.begin(), name.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.';
  });
}

/// The schema parameters the entry gives, each with its JSON path as source.
ParamSet givenParams(const Object& c) {
  ParamSet given;
  for (const auto& item : c.raw().items())
    if (const ParamSpec* spec = findCameraParamSpec(item.key()))
      given.set(*spec, paramFromJson(c, *spec, item.value()), c.keyPath(item.key()));
  return given;
}

/// The entry's "blender" block, a camera in bpy.types.Camera's property names, as schema
/// parameters of `given`: lens (mm, default 50; or angle, radians across the fitted sensor
/// side, as Camera.angle) → focal_length, sensor_width/sensor_height → sensor, sensor_fit →
/// sensor_fit, shift_x/shift_y → blender_shift, clip_start/clip_end → clip. Keys not given
/// keep Blender's defaults (aperture's: 36 x 24 mm, AUTO, no shift); no clip_* key, no
/// clipping (one of them: the other is Blender's default, 0.1 or 1000).
void addBlenderParams(const Object& c, ParamSet& given) {
  const json* block = c.find("blender");
  if (!block) return;
  const Object b(c.file(), c.keyPath("blender"), *block,
                 {"lens", "angle", "sensor_width", "sensor_height", "sensor_fit", "shift_x",
                  "shift_y", "clip_start", "clip_end"});
  auto put = [&](const char* name, ParamValue v, const char* keyA, const char* keyB) {
    const char* key = b.has(keyA) || !*keyB ? keyA : keyB;
    const ParamSpec& spec = *findCameraParamSpec(name);
    if (given.has(name))
      b.fail(b.keyPath(key), cat("sets ", name, ", which ", given.label(spec), " sets as well"));
    given.set(spec, std::move(v), b.keyPath(key));
  };
  const glm::dvec2 sensor(b.number("sensor_width", 36.0), b.number("sensor_height", 24.0));
  SensorFit fit = SensorFit::Auto;
  try {
    fit = parseBlenderSensorFit(b.string("sensor_fit").value_or("AUTO"));
  } catch (const Error& e) {
    b.fail(b.keyPath("sensor_fit"), e.what());
  }
  if (b.has("sensor_width") || b.has("sensor_height"))
    put("sensor", sensor, "sensor_width", "sensor_height");
  if (b.has("sensor_fit"))
    put("sensor_fit", toLowerAscii(*b.string("sensor_fit")), "sensor_fit", "");
  if (b.has("lens") && b.has("angle")) b.fail(b.path(), "give lens or angle, not both");
  if (const std::optional<double> angle = b.number("angle")) {
    if (!(*angle > 0 && *angle < kPi)) b.fail(b.keyPath("angle"), "must be in (0, pi) radians");
    put("focal_length", fittedSensorMm(fit, sensor) / (2.0 * std::tan(*angle / 2.0)), "angle", "");
  } else {
    put("focal_length", b.number("lens", 50.0), "lens", "");
  }
  if (b.has("shift_x") || b.has("shift_y"))
    put("blender_shift", glm::dvec2(b.number("shift_x", 0.0), b.number("shift_y", 0.0)), "shift_x",
        "shift_y");
  if (b.has("clip_start") || b.has("clip_end"))
    put("clip", glm::dvec2(b.number("clip_start", 0.1), b.number("clip_end", 1000.0)), "clip_start",
        "clip_end");
}

void checkFrameKeys(const Object& c, bool orbit, bool keyed) {
  if (orbit && keyed) c.fail(c.path(), "give orbit or keyframes, not both");
  if (orbit || keyed) {
    for (const char* k : {"eye", "at", "dir"})
      if (c.has(k))
        c.fail(c.keyPath(k), cat("not allowed with ", orbit ? "orbit" : "keyframes",
                                 " (the path sets the eye and the look-at point)"));
    return;
  }
  if (c.has("frames"))
    c.fail(c.keyPath("frames"), "only a camera with orbit or keyframes has frames");
  if (!c.has("eye"))
    c.fail(c.keyPath("eye"), "required key is missing (or give orbit or keyframes)");
  if (c.has("at") == c.has("dir")) c.fail(c.path(), "give exactly one of at and dir");
}

int frameCount(const Object& c, int byDefault, size_t framesLeft) {
  const int n = c.integer("frames", byDefault);
  if (n < 1 || size_t(n) > kMaxJobImages)
    c.fail(c.keyPath("frames"), cat(n, ": must be in [1, ", kMaxJobImages, "]"));
  if (size_t(n) > framesLeft)
    c.fail(c.keyPath("frames"), cat("the job would have more than ", kMaxJobImages, " images"));
  return n;
}

std::vector<std::pair<int, CameraParams>> orbitFrames(const Object& c, const CameraParams& base,
                                                      size_t framesLeft) {
  OrbitPath path = parseOrbit(c, base);
  if (!c.has("frames")) c.fail(c.keyPath("frames"), "required key is missing (orbit frames)");
  path.frames = frameCount(c, 1, framesLeft);
  std::vector<std::pair<int, CameraParams>> frames;
  for (int f = 0; f < path.frames; ++f) {
    CameraParams p = base;
    p.eye = orbitEye(path, f);
    p.at = path.centre;
    frames.emplace_back(f, p);
  }
  return frames;
}

std::vector<std::pair<int, CameraParams>> keyframeFrames(const Object& c, const CameraParams& base,
                                                         size_t framesLeft) {
  const std::vector<Keyframe> keys = parseKeyframes(c, base);
  const int last = keys.back().frame;
  if (last == INT_MAX) c.fail(c.keyPath("keyframes"), "frame number too large");
  const int n = frameCount(c, last + 1, framesLeft);
  std::vector<std::pair<int, CameraParams>> frames;
  for (int f = 0; f < n; ++f) {
    const Keyframe k = interpolateKeyframes(keys, f);
    CameraParams p = base;
    p.eye = k.eye;
    p.at = k.at;
    p.up = k.up;
    if (k.fovDeg) p.fovDeg = k.fovDeg;
    frames.emplace_back(f, p);
  }
  return frames;
}

}  // namespace

std::vector<std::string> jobCameraKeys() {
  std::vector<std::string> keys = {"name", "orbit", "keyframes", "frames"};
  for (const ParamSpec* s : allCameraParamSpecs()) keys.emplace_back(s->name);
  keys.emplace_back("blender");
  return keys;
}

namespace {
/// A list of numbers: flat, or (for a 4x4 matrix) four rows of four, read row by row.
std::vector<double> numbersFromJson(const Object& entry, const std::string& where, const json& v,
                                    size_t count) {
  if (!v.is_array() || v.empty())
    entry.fail(where, cat("expected a list of numbers, got ", Object::typeName(v)));
  if (count == 16 && v.size() == 4 && v[0].is_array()) {
    std::vector<double> all;
    for (size_t r = 0; r < 4; ++r) {
      const std::vector<double> row = entry.toNumbers(indexPath(where, r), v[r], 4);
      all.insert(all.end(), row.begin(), row.end());
    }
    return all;
  }
  return entry.toNumbers(where, v, count ? count : v.size());
}
}  // namespace

ParamValue paramFromJson(const Object& entry, const ParamSpec& spec, const json& v) {
  const std::string where = entry.keyPath(spec.name);
  switch (spec.kind) {
    case ParamKind::Number:
      return entry.toNumber(where, v);
    case ParamKind::Integer:
      return entry.toInt(where, v);
    case ParamKind::Vec2: {
      const auto x = entry.toNumbers(where, v, 2);
      return glm::dvec2(x[0], x[1]);
    }
    case ParamKind::Vec3: {
      const auto x = entry.toNumbers(where, v, 3);
      return glm::dvec3(x[0], x[1], x[2]);
    }
    case ParamKind::Size:
      if (!v.is_array() || v.size() != 2)
        entry.fail(where, cat("expected [width, height], got ", Object::typeName(v)));
      return glm::ivec2(entry.toInt(indexPath(where, 0), v[0]),
                        entry.toInt(indexPath(where, 1), v[1]));
    case ParamKind::Flag:
      if (!v.is_boolean())
        entry.fail(where, cat("expected true or false, got ", Object::typeName(v)));
      return v.get<bool>();
    case ParamKind::Choice:
      if (!v.is_string()) entry.fail(where, cat("expected a string, got ", Object::typeName(v)));
      return v.get<std::string>();
    case ParamKind::Numbers:
      return numbersFromJson(entry, where, v, spec.count);
  }
  entry.fail(where, "unsupported parameter kind");
}

JobCamera parseJobCamera(const Object& c, const CameraParams& defaults, size_t framesLeft) {
  JobCamera cam;
  if (!c.has("name")) c.fail(c.keyPath("name"), "required key is missing");
  cam.name = *c.string("name");
  if (!validName(cam.name))
    c.fail(c.keyPath("name"), cat("'", cam.name, "': use 1-128 letters, digits, '_', '-', '.'"));
  const bool orbit = c.has("orbit"), keyed = c.has("keyframes");
  checkFrameKeys(c, orbit, keyed);
  // givenParams and addBlenderParams name the file themselves.
  ParamSet given = givenParams(c);
  addBlenderParams(c, given);
  CameraParams base;
  try {
    base = resolveCameraParams(given, defaults);
  } catch (const Error& e) {
    throw Error(cat(c.file(), ": ", e.what()));
  }
  if (orbit)
    cam.frames = orbitFrames(c, base, framesLeft);
  else if (keyed)
    cam.frames = keyframeFrames(c, base, framesLeft);
  else
    cam.frames.emplace_back(0, base);
  for (auto& [f, p] : cam.frames) {
    try {
      makeCamera(p);
    } catch (const Error& e) {
      c.fail(c.path(), cat("camera '", cam.name, "' frame ", f, ": ", e.what()));
    }
  }
  return cam;
}

}  // namespace aperture::app
