#include "apps/job_camera.h"

#include <algorithm>
#include <cctype>
#include <climits>

#include "apps/camera_paths.h"
#include "cameras/registry.h"

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
  return keys;
}

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
  CameraParams base;
  try {
    base = resolveCameraParams(givenParams(c), defaults);
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
