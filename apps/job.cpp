#include "apps/job.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <initializer_list>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "apps/options.h"
#include "apps/outputs.h"
#include "cameras/registry.h"
#include "core/error.h"
#include "core/units.h"

namespace aperture::app {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kMaxDepth = 32;
constexpr std::uintmax_t kMaxJobBytes = 16u << 20;

/// A JSON object with a fixed set of known keys, read through typed getters whose errors
/// name the file and the JSON path ("cameras[2].eye").
class Object {
 public:
  Object(const std::string& file, std::string path, const json& j,
         std::initializer_list<const char*> known)
      : file_(file), path_(std::move(path)), j_(j) {
    if (!j.is_object()) fail(path_, cat("expected an object, got ", typeName(j)));
    for (const auto& item : j.items()) {
      const bool ok =
          std::any_of(known.begin(), known.end(), [&](const char* k) { return item.key() == k; });
      if (ok) continue;
      std::string list;
      for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
      fail(keyPath(item.key()), cat("unknown key (known: ", list, ")"));
    }
  }

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw Error(cat(file_, ": ", where.empty() ? "(top level)" : where, ": ", what));
  }
  std::string keyPath(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  bool has(const char* key) const { return j_.contains(key); }
  const json* find(const char* key) const {
    auto it = j_.find(key);
    return it == j_.end() ? nullptr : &*it;
  }
  const json& required(const char* key) const {
    const json* v = find(key);
    if (!v) fail(keyPath(key), "required key is missing");
    return *v;
  }

  static std::string typeName(const json& v) {
    if (v.is_number_integer()) return "an integer";
    if (v.is_number()) return "a number";
    if (v.is_string()) return "a string";
    if (v.is_boolean()) return "a boolean";
    if (v.is_array()) return "an array";
    if (v.is_object()) return "an object";
    return "null";
  }

  double toNumber(const std::string& where, const json& v) const {
    if (!v.is_number()) fail(where, cat("expected a number, got ", typeName(v)));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(where, "expected a finite number");
    return x;
  }
  int toInt(const std::string& where, const json& v) const {
    if (v.is_number_unsigned()) {
      if (v.get<uint64_t>() > uint64_t(INT_MAX)) fail(where, "integer out of range");
      return int(v.get<uint64_t>());
    }
    if (!v.is_number_integer()) fail(where, cat("expected an integer, got ", typeName(v)));
    const int64_t x = v.get<int64_t>();
    if (x < INT_MIN || x > INT_MAX) fail(where, "integer out of range");
    return int(x);
  }
  std::vector<double> toNumbers(const std::string& where, const json& v, size_t n) const {
    if (!v.is_array() || v.size() != n)
      fail(where, cat("expected an array of ", n, " numbers, got ", typeName(v)));
    std::vector<double> out;
    for (size_t k = 0; k < n; ++k) out.push_back(toNumber(cat(where, "[", k, "]"), v[k]));
    return out;
  }

  std::optional<double> number(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    return toNumber(keyPath(key), *v);
  }
  double number(const char* key, double def) const { return number(key).value_or(def); }
  std::optional<int> integer(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    return toInt(keyPath(key), *v);
  }
  int integer(const char* key, int def) const { return integer(key).value_or(def); }
  bool boolean(const char* key, bool def) const {
    const json* v = find(key);
    if (!v) return def;
    if (!v->is_boolean()) fail(keyPath(key), cat("expected true or false, got ", typeName(*v)));
    return v->get<bool>();
  }
  std::optional<std::string> string(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    if (!v->is_string()) fail(keyPath(key), cat("expected a string, got ", typeName(*v)));
    return v->get<std::string>();
  }
  std::optional<glm::dvec3> vec3(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    auto x = toNumbers(keyPath(key), *v, 3);
    return glm::dvec3(x[0], x[1], x[2]);
  }
  std::optional<glm::dvec2> vec2(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    auto x = toNumbers(keyPath(key), *v, 2);
    return glm::dvec2(x[0], x[1]);
  }
  const json& array(const char* key) const {
    const json& v = required(key);
    if (!v.is_array()) fail(keyPath(key), cat("expected an array, got ", typeName(v)));
    return v;
  }

 private:
  const std::string& file_;
  std::string path_;
  const json& j_;
};

std::string indexPath(const std::string& path, size_t k) { return cat(path, "[", k, "]"); }

glm::dmat4 rotationDeg(const glm::dvec3& axis, double deg) {
  return glm::rotate(glm::dmat4(1.0), deg * kPi / 180.0, glm::normalize(axis));
}

/// transform: {translate, rotate: {axis, angle} | {euler}, scale}: world = T · R · S · local.
glm::dmat4 parseTransform(const Object& parent, const char* key) {
  const Object t(parent.file(), parent.keyPath(key), parent.required(key),
                 {"translate", "rotate", "scale"});
  glm::dmat4 m(1.0);
  if (auto tr = t.vec3("translate")) m = glm::translate(m, *tr);
  if (t.has("rotate")) {
    const Object r(t.file(), t.keyPath("rotate"), t.required("rotate"), {"axis", "angle", "euler"});
    if (r.has("euler")) {
      if (r.has("axis") || r.has("angle"))
        r.fail(r.path(), "give either euler or axis and angle, not both");
      const glm::dvec3 e = *r.vec3("euler");
      m = m * rotationDeg({0, 0, 1}, e.z) * rotationDeg({0, 1, 0}, e.y) *
          rotationDeg({1, 0, 0}, e.x);
    } else {
      if (!r.has("axis") || !r.has("angle"))
        r.fail(r.path(),
               "expected {\"axis\": [x, y, z], \"angle\": degrees} or {\"euler\": [x, y, z]}");
      const glm::dvec3 axis = *r.vec3("axis");
      if (glm::length(axis) < 1e-12) r.fail(r.keyPath("axis"), "axis has zero length");
      m = m * rotationDeg(axis, *r.number("angle"));
    }
  }
  if (const json* s = t.find("scale")) {
    glm::dvec3 scale;
    if (s->is_array()) {
      auto v = t.toNumbers(t.keyPath("scale"), *s, 3);
      scale = {v[0], v[1], v[2]};
    } else {
      scale = glm::dvec3(t.toNumber(t.keyPath("scale"), *s));
    }
    if (scale.x == 0 || scale.y == 0 || scale.z == 0)
      t.fail(t.keyPath("scale"), "scale must not be zero");
    m = glm::scale(m, scale);
  }
  return m;
}

/// matrix: four rows of four numbers, affine (last row 0 0 0 1), invertible.
glm::dmat4 parseMatrix(const Object& parent, const char* key) {
  const std::string where = parent.keyPath(key);
  const json& v = parent.required(key);
  if (!v.is_array() || v.size() != 4) parent.fail(where, "expected 4 rows of 4 numbers");
  glm::dmat4 m(1.0);
  for (int r = 0; r < 4; ++r) {
    auto row = parent.toNumbers(indexPath(where, size_t(r)), v[size_t(r)], 4);
    for (int c = 0; c < 4; ++c) m[c][r] = row[size_t(c)];
  }
  if (m[0][3] != 0 || m[1][3] != 0 || m[2][3] != 0 || m[3][3] != 1)
    parent.fail(where, "the last row must be [0, 0, 0, 1] (an affine transform)");
  const double det = glm::determinant(glm::dmat3(m));
  if (!std::isfinite(det) || std::abs(det) < 1e-300) parent.fail(where, "matrix is singular");
  return m;
}

bool isProcedural(const std::string& spec) { return spec.rfind("procedural:", 0) == 0; }

std::string resolve(const std::string& baseDir, const std::string& p) {
  if (p.empty() || fs::path(p).is_absolute() || baseDir.empty()) return p;
  return (fs::path(baseDir) / p).lexically_normal().string();
}

/// Fields of a camera entry that are CameraParams fields (every camera flag of the CLI).
void readCameraFields(const Object& c, CameraParams& p) {
  if (auto t = c.string("type")) p.type = *t;
  if (auto v = c.vec3("up")) p.up = *v;
  if (auto v = c.number("fov")) p.fovDeg = *v;
  if (auto v = c.string("fov_axis")) {
    if (*v == "x")
      p.fovAxis = FovAxis::X;
    else if (*v == "y")
      p.fovAxis = FovAxis::Y;
    else if (*v == "diagonal")
      p.fovAxis = FovAxis::Diagonal;
    else
      c.fail(c.keyPath("fov_axis"), cat("'", *v, "' is not one of x, y, diagonal"));
  }
  if (auto v = c.number("d")) p.d = *v;
  if (auto v = c.vec2("viewport")) p.viewport = *v;
  if (auto v = c.number("focal_length")) p.focalLengthMm = *v;
  if (auto v = c.vec2("sensor")) p.sensorMm = *v;
  if (auto v = c.vec2("shift")) p.shift = *v;
  p.architectural = c.boolean("architectural", false);
  if (auto v = c.vec3("oblique_dir")) p.obliqueDir = *v;
  if (auto v = c.vec2("oblique_angles")) p.obliqueAnglesDeg = *v;
  p.apertureRadius = c.number("aperture", 0.0);
  if (auto v = c.number("focus")) p.focusDistance = *v;
  if (auto v = c.vec2("lon")) p.longitudeRangeDeg = *v;
  if (auto v = c.vec2("lat")) p.latitudeRangeDeg = *v;
  p.fisheyeFovDeg = c.number("fisheye_fov", 180.0);
  if (p.d && !p.viewport)
    c.fail(c.keyPath("d"), "d needs viewport (the viewport at that distance)");
}

/// The image-plane defaults of `aperture render`: viewport without d means d = 1, and with
/// none of fov, viewport and focal length the fov is 45 degrees.
void finishImagePlane(CameraParams& p) {
  if (p.viewport && !p.d) p.d = 1.0;
  if (!p.fovDeg && !p.viewport && !p.focalLengthMm) p.fovDeg = 45.0;
}

const std::initializer_list<const char*> kCameraKeys = {"name",
                                                        "type",
                                                        "eye",
                                                        "at",
                                                        "dir",
                                                        "up",
                                                        "fov",
                                                        "fov_axis",
                                                        "d",
                                                        "viewport",
                                                        "focal_length",
                                                        "sensor",
                                                        "shift",
                                                        "architectural",
                                                        "oblique_dir",
                                                        "oblique_angles",
                                                        "aperture",
                                                        "focus",
                                                        "lon",
                                                        "lat",
                                                        "fisheye_fov",
                                                        "orbit",
                                                        "keyframes",
                                                        "frames"};

bool validName(const std::string& name) {
  if (name.empty() || name.size() > 128 || name == "." || name == "..") return false;
  return std::all_of(name.begin(), name.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.';
  });
}

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

}  // namespace

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

std::string expandOutputPattern(const std::string& pattern, const std::string& camera, int frame) {
  std::string out;
  for (size_t i = 0; i < pattern.size(); ++i) {
    const char ch = pattern[i];
    if (ch == '}') throw Error(cat("'", pattern, "': '}' without '{' at position ", i));
    if (ch != '{') {
      out += ch;
      continue;
    }
    const size_t close = pattern.find('}', i);
    if (close == std::string::npos)
      throw Error(cat("'", pattern, "': '{' at position ", i, " is not closed"));
    const std::string field = pattern.substr(i + 1, close - i - 1);
    if (field == "camera") {
      out += camera;
    } else if (field == "frame") {
      out += std::to_string(frame);
    } else if (field.size() >= 9 && field.compare(0, 7, "frame:0") == 0 && field.back() == 'd') {
      const std::string digits = field.substr(7, field.size() - 8);
      const bool numeric =
          !digits.empty() && digits.size() <= 2 &&
          std::all_of(digits.begin(), digits.end(), [](char d) { return d >= '0' && d <= '9'; });
      const int width = numeric ? std::stoi(digits) : 0;
      if (width < 1 || width > 20)
        throw Error(
            cat("'", pattern, "': '{", field, "}' needs a width in 1..20, e.g. {frame:04d}"));
      std::string n = std::to_string(frame);
      if (int(n.size()) < width) n.insert(0, size_t(width) - n.size(), '0');
      out += n;
    } else {
      throw Error(cat("'", pattern, "': unknown placeholder '{", field,
                      "}' (known: {camera}, {frame}, {frame:0Nd})"));
    }
    i = close;
  }
  return out;
}

Job parseJobText(const std::string& text, const std::string& name, const std::string& baseDir) {
  json root;
  try {
    json::parser_callback_t limitDepth = [&](int depth, json::parse_event_t, json&) {
      if (depth > kMaxDepth) throw Error(cat(name, ": nested deeper than ", kMaxDepth, " levels"));
      return true;
    };
    root = json::parse(text, limitDepth);
  } catch (const json::exception& e) {
    throw Error(cat(name, ": not valid JSON: ", e.what()));
  }

  const Object top(name, "", root,
                   {"scene", "cameras", "aovs", "size", "spp", "output", "preview", "preview_range",
                    "compression", "half", "performance", "preset"});
  Job job;
  job.path = name;
  // A preset supplies the defaults of spp, compression, half, bvh_quality and robust; keys
  // given explicitly win, as flags do on the command line.
  const Preset* preset = nullptr;
  if (const auto presetName = top.string("preset")) {
    try {
      preset = &findPreset(*presetName);
    } catch (const Error& e) {
      top.fail("preset", e.what());
    }
    job.build.quality = parseBvhQuality(preset->bvhQuality);
    job.build.robust = preset->robust;
  }

  // Image and output settings.
  if (const json* a = top.find("aovs")) {
    std::string list;
    if (a->is_string()) {
      list = a->get<std::string>();
    } else if (a->is_array()) {
      for (size_t k = 0; k < a->size(); ++k) {
        if (!(*a)[k].is_string())
          top.fail(indexPath("aovs", k), cat("expected a string, got ", Object::typeName((*a)[k])));
        list += (list.empty() ? "" : ",") + (*a)[k].get<std::string>();
      }
    } else {
      top.fail("aovs", cat("expected a string or an array of strings, got ", Object::typeName(*a)));
    }
    try {
      job.aovs = parseAovList(list);
    } catch (const Error& e) {
      top.fail("aovs", e.what());
    }
    if (job.aovs == 0) top.fail("aovs", "no AOV requested");
  } else {
    job.aovs = parseAovList("color,depth");
  }
  job.width = 960;
  job.height = 540;
  if (const json* s = top.find("size")) {
    if (!s->is_array() || s->size() != 2)
      top.fail("size", cat("expected [width, height], got ", Object::typeName(*s)));
    job.width = top.toInt("size[0]", (*s)[0]);
    job.height = top.toInt("size[1]", (*s)[1]);
    constexpr int kMaxSide = 65536;
    constexpr double kMaxPixels = 1 << 28;
    if (job.width < 1 || job.height < 1 || job.width > kMaxSide || job.height > kMaxSide ||
        double(job.width) * double(job.height) > kMaxPixels)
      top.fail("size", cat("[", job.width, ", ", job.height,
                           "]: width and height must be in [1, 65536] with at most ", kMaxPixels,
                           " pixels"));
  }
  job.render.spp = top.integer("spp", preset ? preset->spp : 1);
  if (job.render.spp < 1 || job.render.spp > 65536)
    top.fail("spp", cat(job.render.spp, ": must be in [1, 65536]"));
  if (!top.has("output")) top.fail("output", "required key is missing");
  job.outputPattern = *top.string("output");
  job.previewPattern = top.string("preview").value_or("");
  try {
    job.exr.compression = parseExrCompression(
        top.string("compression").value_or(preset ? preset->compression : "zip"));
  } catch (const Error& e) {
    top.fail("compression", e.what());
  }
  job.exr.halfColor = top.boolean("half", preset ? preset->halfColor : false);

  // Performance.
  if (top.has("performance")) {
    const Object p(name, "performance", top.required("performance"),
                   {"packet", "tile", "threads", "bvh_quality", "robust", "compact", "cull"});
    job.render.packetWidth = p.integer("packet", 16);
    const int w = job.render.packetWidth;
    if (w != 1 && w != 4 && w != 8 && w != 16)
      p.fail(p.keyPath("packet"), cat(w, ": must be 1, 4, 8 or 16"));
    job.render.tileSize = p.integer("tile", 32);
    if (job.render.tileSize < 4 || job.render.tileSize > 4096 || job.render.tileSize % 4)
      p.fail(p.keyPath("tile"), cat(job.render.tileSize, ": must be a multiple of 4 in [4, 4096]"));
    job.threads = p.integer("threads", 0);
    if (job.threads < 0 || job.threads > 4096)
      p.fail(p.keyPath("threads"), cat(job.threads, ": must be in [0, 4096] (0 = all cores)"));
    try {
      job.build.quality =
          parseBvhQuality(p.string("bvh_quality").value_or(bvhQualityName(job.build.quality)));
    } catch (const Error& e) {
      p.fail(p.keyPath("bvh_quality"), e.what());
    }
    job.build.robust = p.boolean("robust", job.build.robust);
    job.build.compact = p.boolean("compact", false);
    job.cull = p.boolean("cull", false);
  }
  try {
    validateRenderSettings(job.render);
  } catch (const Error& e) {
    top.fail("performance", e.what());
  }

  // Scene: every file must exist before anything is loaded.
  if (!top.has("scene")) top.fail("scene", "required key is missing");
  const Object scene(name, "scene", top.required("scene"), {"meshes", "placement"});
  const std::string placement = scene.string("placement").value_or("camera-relative");
  if (placement == "world-space")
    job.placement = Placement::WorldSpace;
  else if (placement != "camera-relative")
    scene.fail(scene.keyPath("placement"),
               cat("'", placement, "': must be camera-relative or world-space"));
  const json& meshes = scene.array("meshes");
  if (meshes.empty()) scene.fail("scene.meshes", "needs at least one mesh");
  for (size_t k = 0; k < meshes.size(); ++k) {
    const Object m(name, indexPath("scene.meshes", k), meshes[k], {"path", "transform", "matrix"});
    if (!m.has("path")) m.fail(m.keyPath("path"), "required key is missing");
    JobMesh mesh;
    const std::string given = *m.string("path");
    if (given.empty()) m.fail(m.keyPath("path"), "empty path");
    mesh.spec = isProcedural(given) ? given : resolve(baseDir, given);
    if (!isProcedural(given)) {
      std::error_code ec;
      if (fs::is_directory(mesh.spec, ec))
        m.fail(m.keyPath("path"), cat("'", mesh.spec, "': is a directory, not a mesh file"));
      if (!fs::is_regular_file(mesh.spec, ec))
        m.fail(m.keyPath("path"),
               cat("'", mesh.spec,
                   "': ", fs::exists(mesh.spec, ec) ? "not a regular file" : "no such file"));
    }
    if (m.has("transform") && m.has("matrix"))
      m.fail(m.path(), "give transform or matrix, not both");
    if (m.has("transform")) mesh.worldFromMesh = parseTransform(m, "transform");
    if (m.has("matrix")) mesh.worldFromMesh = parseMatrix(m, "matrix");
    job.meshes.push_back(mesh);
  }

  // Cameras: each entry expands into its frames; every frame's camera is constructed.
  if (!top.has("cameras")) top.fail("cameras", "required key is missing");
  const json& cameras = top.array("cameras");
  if (cameras.empty()) top.fail("cameras", "needs at least one camera");
  std::set<std::string> names;
  for (size_t ci = 0; ci < cameras.size(); ++ci) {
    const Object c(name, indexPath("cameras", ci), cameras[ci], kCameraKeys);
    if (!c.has("name")) c.fail(c.keyPath("name"), "required key is missing");
    const std::string camName = *c.string("name");
    if (!validName(camName))
      c.fail(c.keyPath("name"), cat("'", camName, "': use 1-128 letters, digits, '_', '-', '.'"));
    if (!names.insert(camName).second)
      c.fail(c.keyPath("name"), cat("'", camName, "': a camera of that name already exists"));

    CameraParams base;
    base.width = job.width;
    base.height = job.height;
    base.spp = job.render.spp;
    readCameraFields(c, base);
    const bool orbit = c.has("orbit"), keyed = c.has("keyframes");
    if (orbit && keyed) c.fail(c.path(), "give orbit or keyframes, not both");
    if (orbit || keyed) {
      for (const char* k : {"eye", "at", "dir"})
        if (c.has(k))
          c.fail(c.keyPath(k), cat("not allowed with ", orbit ? "orbit" : "keyframes",
                                   " (the path sets the eye and the look-at point)"));
    } else {
      if (c.has("frames"))
        c.fail(c.keyPath("frames"), "only a camera with orbit or keyframes has frames");
      if (!c.has("eye"))
        c.fail(c.keyPath("eye"), "required key is missing (or give orbit or keyframes)");
      if (c.has("at") == c.has("dir")) c.fail(c.path(), "give exactly one of at and dir");
    }

    // The per-frame parameters, in frame order.
    std::vector<std::pair<int, CameraParams>> frames;
    auto frameCount = [&](int def) {
      const int n = c.integer("frames", def);
      if (n < 1 || size_t(n) > kMaxJobImages)
        c.fail(c.keyPath("frames"), cat(n, ": must be in [1, ", kMaxJobImages, "]"));
      if (job.images.size() + size_t(n) > kMaxJobImages)
        c.fail(c.keyPath("frames"), cat("the job would have more than ", kMaxJobImages, " frames"));
      return n;
    };
    if (orbit) {
      OrbitPath path = parseOrbit(c, base);
      if (!c.has("frames")) c.fail(c.keyPath("frames"), "required key is missing (orbit frames)");
      path.frames = frameCount(1);
      for (int f = 0; f < path.frames; ++f) {
        CameraParams p = base;
        p.eye = orbitEye(path, f);
        p.at = path.centre;
        frames.emplace_back(f, p);
      }
    } else if (keyed) {
      const std::vector<Keyframe> keys = parseKeyframes(c, base);
      const int last = keys.back().frame;
      if (last == INT_MAX) c.fail(c.keyPath("keyframes"), "frame number too large");
      const int n = frameCount(last + 1);
      for (int f = 0; f < n; ++f) {
        const Keyframe k = interpolateKeyframes(keys, f);
        CameraParams p = base;
        p.eye = k.eye;
        p.at = k.at;
        p.up = k.up;
        if (k.fovDeg) p.fovDeg = k.fovDeg;
        frames.emplace_back(f, p);
      }
    } else {
      CameraParams p = base;
      p.eye = *c.vec3("eye");
      p.at = c.vec3("at");
      p.dir = c.vec3("dir");
      frames.emplace_back(0, p);
    }

    for (auto& [f, p] : frames) {
      finishImagePlane(p);
      try {
        makeCamera(p);
      } catch (const Error& e) {
        c.fail(c.path(), cat("camera '", camName, "' frame ", f, ": ", e.what()));
      }
      JobImage jf;
      jf.index = job.images.size();
      jf.camera = camName;
      jf.frame = f;
      jf.params = p;
      try {
        jf.output = resolve(baseDir, expandOutputPattern(job.outputPattern, camName, f));
      } catch (const Error& e) {
        top.fail("output", e.what());
      }
      if (!job.previewPattern.empty()) {
        try {
          jf.preview = resolve(baseDir, expandOutputPattern(job.previewPattern, camName, f));
        } catch (const Error& e) {
          top.fail("preview", e.what());
        }
      }
      job.images.push_back(std::move(jf));
    }
  }

  // Outputs: checked as `aperture render` checks --out, --preview and --preview-range
  // (apps/outputs.h); one file per frame.
  if (const auto range = top.vec2("preview_range")) {
    try {
      checkPreviewRange(*range);
    } catch (const Error& e) {
      top.fail("preview_range", cat("[", range->x, ", ", range->y, "]: ", e.what()));
    }
    if (job.previewPattern.empty()) top.fail("preview_range", "needs a \"preview\" pattern");
    job.preview.depthRange = *range;
  }
  job.outputDirectory = resolve(baseDir, patternDirectory(job.outputPattern));
  try {
    checkJobOutputs(job, job.outputDirectory,
                    resolve(baseDir, patternDirectory(job.previewPattern)));
  } catch (const Error& e) {
    throw Error(cat(name, ": ", e.what()));
  }
  std::map<std::string, const JobImage*> used;
  for (const JobImage& f : job.images) {
    for (const std::string* out : {&f.output, &f.preview}) {
      if (out->empty()) continue;
      const char* key = out == &f.output ? "output" : "preview";
      auto [it, fresh] = used.emplace(*out, &f);
      if (!fresh)
        top.fail(key, cat("camera '", f.camera, "' frame ", f.frame, " and camera '",
                          it->second->camera, "' frame ", it->second->frame, " both write '", *out,
                          "' (use {camera} and {frame} in the pattern)"));
    }
  }
  return job;
}

Job parseJob(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw Error(cat(path, ": no such job file"));
  const std::uintmax_t bytes = fs::file_size(path, ec);
  if (ec || bytes > kMaxJobBytes)
    throw Error(cat(path, ": job file too large (", bytes, " bytes; at most ", kMaxJobBytes, ")"));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat(path, ": cannot open the job file"));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(cat(path, ": cannot read the job file"));
  return parseJobText(text.str(), path, fs::path(path).parent_path().string());
}

}  // namespace aperture::app
