#include "apps/jobs/job.h"

#include <algorithm>
#include <cctype>
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

#include "apps/jobs/job_camera.h"
#include "apps/jobs/job_json.h"
#include "apps/jobs/job_outputs.h"
#include "apps/services/camera_file_params.h"
#include "apps/services/presets.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/engine/layers.h"
#include "core/io/dataset_image.h"
#include "core/mesh/mesh.h"
#include "core/mesh/scene_file.h"
#include "core/util/error.h"
#include "core/util/spelling.h"
#include "core/util/units.h"

namespace aperture::app {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kMaxDepth = 32;
constexpr std::uintmax_t kMaxJobBytes = 16u << 20;

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

}  // namespace

std::string expandOutputPattern(const std::string& pattern, const std::string& camera, int frame,
                                const std::string& image) {
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
    } else if (field == "image") {
      if (image.empty())
        throw Error(cat("'", pattern, "': {image} needs cameras from a file (\"cameras\": ",
                        "{\"from\": PATH})"));
      out += renderNameOf(image, "");
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
                      "}' (known: {camera}, {frame}, {frame:0Nd}, {image}; {scene} in a job with ",
                      "\"scenes\")"));
    }
    i = close;
  }
  return out;
}

namespace {

json parseJsonText(const std::string& text, const std::string& name) {
  try {
    json::parser_callback_t limitDepth = [&](int depth, json::parse_event_t, json&) {
      if (depth > kMaxDepth) throw Error(cat(name, ": nested deeper than ", kMaxDepth, " levels"));
      return true;
    };
    return json::parse(text, limitDepth);
  } catch (const json::exception& e) {
    throw Error(cat(name, ": not valid JSON: ", e.what()));
  }
}

/// "preset": the defaults of spp, compression, half, bvh_quality and robust; keys given
/// explicitly win, as flags do on the command line.
const Preset* readPreset(const Object& top, Job& job) {
  const auto presetName = top.string("preset");
  if (!presetName) return nullptr;
  const Preset* preset = nullptr;
  try {
    preset = &findPreset(*presetName);
  } catch (const Error& e) {
    top.fail(top.keyPath("preset"), e.what());
  }
  job.build.quality = parseBvhQuality(preset->bvhQuality);
  job.build.robust = preset->robust;
  return preset;
}

/// "aovs": a comma-separated string or an array of names; default color,depth.
AovSet readAovs(const Object& top) {
  const json* a = top.find("aovs");
  if (!a) return parseAovSet("color,depth");
  std::string list;
  if (a->is_string()) {
    list = a->get<std::string>();
  } else if (a->is_array()) {
    for (size_t k = 0; k < a->size(); ++k) {
      if (!(*a)[k].is_string())
        top.fail(indexPath(top.keyPath("aovs"), k),
                 cat("expected a string, got ", Object::typeName((*a)[k])));
      list += (list.empty() ? "" : ",") + (*a)[k].get<std::string>();
    }
  } else {
    top.fail(top.keyPath("aovs"),
             cat("expected a string or an array of strings, got ", Object::typeName(*a)));
  }
  AovSet aovs;
  try {
    aovs = parseAovSet(list);
  } catch (const Error& e) {
    top.fail(top.keyPath("aovs"), e.what());
  }
  if (aovs.empty()) top.fail(top.keyPath("aovs"), "no AOV requested");
  return aovs;
}

/// Top-level "size" and "spp": the defaults of every camera (a camera may set its own),
/// checked by the camera schema.
CameraParams readCameraDefaults(const Object& top, const Preset* preset) {
  ParamSet given;
  for (const char* key : {"size", "spp"})
    if (const json* v = top.find(key)) {
      const ParamSpec& spec = *findCameraParamSpec(key);
      given.set(spec, paramFromJson(top, spec, *v), key);
    }
  CameraParams defaults;
  if (preset) defaults.spp = preset->spp;
  try {
    return resolveCameraParams(given, defaults);
  } catch (const Error& e) {
    throw Error(cat(top.file(), ": ", e.what()));
  }
}

/// The "aov" of an "outputs" entry: a string, or (for an EXR) an array of strings.
std::string outputAovText(const Object& entry) {
  const json* a = entry.find("aov");
  if (!a) return "all";
  if (a->is_string()) return a->get<std::string>();
  if (!a->is_array()) entry.fail(entry.keyPath("aov"), "expected an AOV name or a list of them");
  std::string list;
  for (size_t k = 0; k < a->size(); ++k) {
    if (!(*a)[k].is_string())
      entry.fail(indexPath(entry.keyPath("aov"), k), "expected an AOV name (a string)");
    list += (list.empty() ? "" : ",") + (*a)[k].get<std::string>();
  }
  return list;
}

/// Refuses an AOV the job does not render: outputs name AOVs of "aovs", they add none.
void checkAmongJobAovs(const Object& entry, const AovSet& wanted, const AovSet& job) {
  bool among = (wanted.mask & ~job.mask) == 0;
  for (const PropertyAov& p : wanted.properties)
    among =
        among && std::find(job.properties.begin(), job.properties.end(), p) != job.properties.end();
  if (!among)
    entry.fail(entry.keyPath("aov"), cat("'", aovListString(wanted), "' is not among the job's ",
                                         "\"aovs\" (", aovListString(job), "); add it there"));
}

/// One "outputs" entry: {"aov": NAME, "path": PATTERN}. A .exr path is the job's EXR (its
/// "aov" is "all" or every AOV of the job: an EXR holds them all); any other path is a
/// dataset file of one AOV.
void readOutputEntry(const Object& entry, const std::string& baseDir, Job& job) {
  if (!entry.has("path")) entry.fail(entry.keyPath("path"), "required key is missing");
  const std::string pattern = *entry.string("path");
  const std::string aovText = outputAovText(entry);
  AovSet wanted;
  try {
    wanted = aovText == "all" ? job.aovs : parseAovSet(aovText);
  } catch (const Error& e) {
    entry.fail(entry.keyPath("aov"), e.what());
  }
  checkAmongJobAovs(entry, wanted, job.aovs);
  if (!datasetFormatOf(pattern)) {
    if (lowerExtension(pattern) != ".exr")
      entry.fail(entry.keyPath("path"), cat("'", pattern, "': unknown extension; supported: .exr ",
                                            join(datasetExtensions(), " ")));
    if (!job.outputPattern.empty())
      entry.fail(entry.keyPath("path"),
                 "the job already writes an EXR (\"output\" or an "
                 "earlier entry); give one");
    if (!(wanted == job.aovs))
      entry.fail(entry.keyPath("aov"),
                 cat("an EXR holds every AOV of the job (", aovListString(job.aovs),
                     "): give \"all\"; write ", "single AOVs as .npy, .tif, .pfm or .png"));
    job.outputPattern = pattern;
    return;
  }
  if (aovText == "all" || aovText.find(',') != std::string::npos)
    entry.fail(entry.keyPath("aov"),
               cat("'", aovText, "': a ", datasetFormatName(*datasetFormatOf(pattern)),
                   " file holds one AOV; give one entry per AOV"));
  job.datasets.push_back({aovText, pattern, resolve(baseDir, patternDirectory(pattern))});
}

void readOutputSettings(const Object& top, const Preset* preset, const std::string& baseDir,
                        Job& job) {
  if (!top.has("output") && !top.has("outputs"))
    top.fail(top.keyPath("output"), "required key is missing (give \"output\" or \"outputs\")");
  job.outputPattern = top.string("output").value_or("");
  if (top.has("outputs")) {
    const json& entries = top.array("outputs");
    if (entries.empty()) top.fail(top.keyPath("outputs"), "needs at least one entry");
    for (size_t k = 0; k < entries.size(); ++k)
      readOutputEntry(
          Object(top.file(), indexPath(top.keyPath("outputs"), k), entries[k], {"aov", "path"}),
          baseDir, job);
  }
  job.writesExr = !job.outputPattern.empty();
  if (top.has("depth_scale")) {
    job.dataset.depthScale = *top.number("depth_scale");
    try {
      checkDepthScale("depth_scale", job.dataset.depthScale);
    } catch (const Error& e) {
      top.fail(top.keyPath("depth_scale"), e.what());
    }
  }
  job.previewPattern = top.string("preview").value_or("");
  try {
    job.exr.compression = parseExrCompression(
        top.string("compression").value_or(preset ? preset->compression : "zip"));
  } catch (const Error& e) {
    top.fail(top.keyPath("compression"), e.what());
  }
  job.exr.halfColor = top.boolean("half", preset ? preset->halfColor : false);
}

/// "deep" (default false): the layered hits go to <EXR stem>.deep.exr (core/exr/exr_deep.h), which
/// needs "layers" and an EXR.
void readDeep(const Object& top, Job& job) {
  job.exr.layersInDeepFile = top.boolean("deep", false);
  if (!job.exr.layersInDeepFile) return;
  if (job.aovs.layers == 0)
    top.fail(top.keyPath("deep"),
             "\"deep\": true needs \"layers\": K (the deep file holds the layered hits)");
  if (!job.writesExr)
    top.fail(top.keyPath("deep"),
             "\"deep\": true needs an EXR output (the deep file goes beside the EXR)");
}

/// "normal_frame" (world|opencv|opengl, default world) and "id_counts" (default false).
void readMeshDataKeys(const Object& top, Job& job) {
  try {
    job.render.normalFrame = parseNormalFrame(top.string("normal_frame").value_or("world"));
  } catch (const Error& e) {
    top.fail(top.keyPath("normal_frame"), e.what());
  }
  job.idCounts = top.boolean("id_counts", false);
}

void readPerformance(const Object& top, Job& job) {
  if (top.has("performance")) {
    const Object p(
        top.file(), top.keyPath("performance"), top.required("performance"),
        {"packet", "tile", "threads", "bvh_quality", "robust", "compact", "bvh_chunk", "cull"});
    job.render.packetWidth = p.integer("packet", 16);
    job.render.tileSize = p.integer("tile", 32);
    job.threads = p.integer("threads", 0);
    if (job.threads < 0 || job.threads > 4096)
      p.fail(p.keyPath("threads"), cat(job.threads, ": must be in [0, 4096] (0 = all cores)"));
    try {
      job.build.quality =
          parseBvhQuality(p.string("bvh_quality").value_or(bvhQualityName(job.build.quality)));
    } catch (const Error& e) {
      p.fail(p.keyPath("bvh_quality"), e.what());
    }
    // Robust (watertight) traversal is the default; "robust": false opts out, as --no-robust.
    job.build.robust = p.boolean("robust", job.build.robust);
    job.build.compact = p.boolean("compact", false);
    const int chunk = p.integer("bvh_chunk", int(kBvhChunkTriangles));
    try {
      job.build.bvhChunkTriangles = checkedBvhChunkTriangles(chunk, "bvh_chunk");
    } catch (const Error& e) {
      p.fail(p.keyPath("bvh_chunk"), e.what());
    }
    job.cull = p.boolean("cull", false);
  }
  try {
    validateRenderSettings(job.render);
  } catch (const Error& e) {
    top.fail(top.keyPath("performance"), e.what());
  }
}

MeshPlacement readMesh(const Object& m, const std::string& baseDir) {
  if (!m.has("path")) m.fail(m.keyPath("path"), "required key is missing");
  MeshPlacement mesh;
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
  if (m.has("transform") && m.has("matrix")) m.fail(m.path(), "give transform or matrix, not both");
  if (m.has("transform")) mesh.worldFromMesh = parseTransform(m, "transform");
  if (m.has("matrix")) mesh.worldFromMesh = parseMatrix(m, "matrix");
  return mesh;
}

/// "scene": every mesh file must exist before anything is loaded.
void readScene(const Object& top, const std::string& baseDir, Job& job) {
  if (!top.has("scene")) top.fail(top.keyPath("scene"), "required key is missing");
  const Object scene(top.file(), top.keyPath("scene"), top.required("scene"),
                     {"meshes", "placement", "gltf_scene"});
  const std::string placement = scene.string("placement").value_or("camera-relative");
  if (placement == "world-space")
    job.placement = Placement::WorldSpace;
  else if (placement != "camera-relative")
    scene.fail(scene.keyPath("placement"),
               cat("'", placement, "': must be camera-relative or world-space"));
  const json& meshes = scene.array("meshes");
  if (meshes.empty()) scene.fail(scene.keyPath("meshes"), "needs at least one mesh");
  for (size_t k = 0; k < meshes.size(); ++k) {
    const Object m(top.file(), indexPath(scene.keyPath("meshes"), k), meshes[k],
                   {"path", "transform", "matrix"});
    job.meshes.push_back(readMesh(m, baseDir));
  }
  if (const std::optional<int> index = scene.integer("gltf_scene")) {
    if (*index < 0) scene.fail(scene.keyPath("gltf_scene"), cat(*index, ": must be >= 0"));
    if (std::none_of(job.meshes.begin(), job.meshes.end(),
                     [](const MeshPlacement& p) { return isGltfPath(p.spec); }))
      scene.fail(scene.keyPath("gltf_scene"),
                 "no mesh is a glTF file (.gltf, .glb) to choose a scene of");
    job.gltfScene = index;
  }
}

std::string expandFor(const Object& top, const char* key, const std::string& pattern,
                      const std::string& baseDir, const std::string& camera, int frame,
                      const std::string& image = "") {
  try {
    return resolve(baseDir, expandOutputPattern(pattern, camera, frame, image));
  } catch (const Error& e) {
    top.fail(top.keyPath(key), e.what());
  }
}

/// The files of one image: the EXR, dataset and preview patterns expanded, and the list of
/// every file in writing order.
void expandImageFiles(const Object& top, const std::string& baseDir, const Job& job,
                      JobImage& image, const std::string& imageName = "") {
  const std::string& camera = image.camera;
  if (job.writesExr)
    image.output =
        expandFor(top, "output", job.outputPattern, baseDir, camera, image.frame, imageName);
  for (const JobDatasetOutput& d : job.datasets)
    image.datasets.push_back(
        {d.aov, expandFor(top, "outputs", d.pattern, baseDir, camera, image.frame, imageName)});
  if (!job.writesExr) image.output = image.datasets.front().path;
  if (!job.previewPattern.empty())
    image.preview =
        expandFor(top, "preview", job.previewPattern, baseDir, camera, image.frame, imageName);
  image.files = viewFilePaths(job.writesExr ? image.output : "", image.preview, image.datasets,
                              job.exr.layersInDeepFile);
}

/// "cameras": {"from": PATH, "images": [NAME, ...]}: every image of a camera file (or those
/// listed, in the order listed), each a calibrated camera named by its image name.
void readCameraFileImages(const Object& top, const CameraParams& defaults,
                          const std::string& baseDir, Job& job) {
  const Object c(top.file(), top.keyPath("cameras"), top.required("cameras"), {"from", "images"});
  const std::optional<std::string> from = c.string("from");
  if (!from) c.fail(c.keyPath("from"), "required key is missing");
  std::vector<std::string> names;
  if (const json* list = c.find("images")) {
    if (!list->is_array()) c.fail(c.keyPath("images"), "expected an array of image names");
    for (size_t k = 0; k < list->size(); ++k) {
      if (!(*list)[k].is_string())
        c.fail(indexPath(c.keyPath("images"), k), "expected an image name (a string)");
      names.push_back((*list)[k].get<std::string>());
    }
  }
  // A glTF camera has no image size of its own: the job's "size", else the default height.
  GltfImageSize gltfSize;
  gltfSize.defaultHeight = defaults.height;
  if (top.has("size")) {
    gltfSize.width = defaults.width;
    gltfSize.height = defaults.height;
  }
  try {
    const CameraFile file =
        readCameraFile(resolve(baseDir, *from), CameraFileOptions{job.gltfScene});
    const std::vector<const CalibratedImage*> images =
        selectImages(file, names, c.keyPath("images"));
    if (images.size() > kMaxJobImages)
      c.fail(c.keyPath("from"), cat(images.size(), " images; at most ", kMaxJobImages));
    for (const CalibratedImage* im : images) {
      JobImage image;
      image.index = job.images.size();
      image.camera = im->name;
      image.params = resolveCameraParams(imageParamSet(file, *im, gltfSize), defaults);
      if (image.params.type == "calibrated")
        calibratedSensorOf(image.params);  // the lens is checked now; its table is built later
      expandImageFiles(top, baseDir, job, image, im->name);
      job.images.push_back(std::move(image));
    }
  } catch (const Error& e) {
    throw Error(cat(top.file(), ": ", e.what()));
  }
}

/// "cameras": each entry expands into its images, in job order.
void readCameras(const Object& top, const CameraParams& defaults, const std::string& baseDir,
                 Job& job) {
  if (!top.has("cameras")) top.fail(top.keyPath("cameras"), "required key is missing");
  if (top.required("cameras").is_object()) return readCameraFileImages(top, defaults, baseDir, job);
  const json& cameras = top.array("cameras");
  if (cameras.empty()) top.fail(top.keyPath("cameras"), "needs at least one camera");
  std::set<std::string> names;
  for (size_t ci = 0; ci < cameras.size(); ++ci) {
    const Object c(top.file(), indexPath(top.keyPath("cameras"), ci), cameras[ci], jobCameraKeys());
    const JobCamera cam = parseJobCamera(c, defaults, kMaxJobImages - job.images.size());
    if (!names.insert(cam.name).second)
      c.fail(c.keyPath("name"), cat("'", cam.name, "': a camera of that name already exists"));
    for (const auto& [f, p] : cam.frames) {
      JobImage image;
      image.index = job.images.size();
      image.camera = cam.name;
      image.frame = f;
      image.params = p;
      expandImageFiles(top, baseDir, job, image);
      job.images.push_back(std::move(image));
    }
  }
}

/// Outputs: checked as `aperture render` checks --out, --preview and --preview-range
/// (apps/jobs/job_outputs.h); one file per image.
void checkOutputs(const Object& top, const std::string& baseDir, Job& job) {
  if (const auto range = top.vec2("preview_range")) {
    try {
      checkPreviewRange(*range);
    } catch (const Error& e) {
      top.fail(top.keyPath("preview_range"), cat("[", range->x, ", ", range->y, "]: ", e.what()));
    }
    if (job.previewPattern.empty())
      top.fail(top.keyPath("preview_range"), "needs a \"preview\" pattern");
    job.preview.depthRange = *range;
  }
  job.outputDirectory = job.writesExr ? resolve(baseDir, patternDirectory(job.outputPattern))
                                      : job.datasets.front().directory;
  try {
    checkJobOutputs(job, job.outputDirectory,
                    resolve(baseDir, patternDirectory(job.previewPattern)));
  } catch (const Error& e) {
    throw Error(cat(top.file(), ": ", e.what()));
  }
  std::map<std::string, const JobImage*> used;
  for (const JobImage& f : job.images) {
    for (const std::string& out : f.files) {
      const char* key = out == f.preview                   ? "preview"
                        : job.writesExr && out == f.output ? "output"
                                                           : "outputs";
      auto [it, fresh] = used.emplace(out, &f);
      if (!fresh)
        top.fail(top.keyPath(key),
                 cat("camera '", f.camera, "' frame ", f.frame, " and camera '", it->second->camera,
                     "' frame ", it->second->frame, " both write '", out,
                     "' (use {camera} and {frame}, or {image}, in the patterns)"));
    }
  }
}

}  // namespace

namespace {

/// The keys of a job's top level (of a "scenes" entry too, which adds "name").
const std::vector<std::string>& jobKeys() {
  static const std::vector<std::string> keys = {
      "scene",        "cameras",   "aovs",        "size",    "spp",
      "output",       "outputs",   "depth_scale", "preview", "preview_range",
      "compression",  "half",      "performance", "preset",  "camera_files",
      "normal_frame", "id_counts", "layers",      "deep",    "lidars"};
  return keys;
}

/// A job's top level, already parsed as JSON. `placed` names the keys that an entry of
/// "scenes" gave, with the path each was written at.
Job parseJobJson(const json& root, const std::string& name, const std::string& baseDir,
                 const std::vector<std::pair<std::string, std::string>>& placed = {}) {
  Object top(name, "", root, jobKeys());
  for (const auto& [key, where] : placed) top.placeKey(key, where);
  Job job;
  job.path = name;
  const Preset* preset = readPreset(top, job);
  job.aovs = readAovs(top);
  if (const std::optional<int> layers = top.integer("layers")) {
    try {
      checkLayerCount(*layers, "layers");
    } catch (const Error& e) {
      top.fail(top.keyPath("layers"), e.what());
    }
    job.aovs.layers = *layers;
  }
  const CameraParams defaults = readCameraDefaults(top, preset);
  job.width = defaults.width;
  job.height = defaults.height;
  job.render.spp = defaults.spp;
  readOutputSettings(top, preset, baseDir, job);
  readDeep(top, job);
  readPerformance(top, job);
  readScene(top, baseDir, job);
  readCameras(top, defaults, baseDir, job);
  job.cameraFiles = top.boolean("camera_files", top.required("cameras").is_object());
  readMeshDataKeys(top, job);
  checkOutputs(top, baseDir, job);
  job.lidars = readJobLidars(top, baseDir);
  return job;
}

constexpr size_t kMaxJobScenes = 100000;

/// A scene's name goes into file names through {scene}: letters, digits, '_', '-' and '.',
/// not starting with '.'.
void checkSceneName(const Object& entry, const std::string& name) {
  const bool safe =
      !name.empty() && name.size() <= 200 && name.front() != '.' &&
      std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
      });
  if (!safe)
    entry.fail(entry.keyPath("name"),
               cat("'", name, "': a scene name is 1 to 200 letters, digits, '_', '-' or '.', ",
                   "not starting with '.' (it names files through {scene})"));
}

/// Replaces {scene} in one output pattern of an entry's job; with several scenes the pattern
/// must have it, or the scenes would write the same files.
void expandScenePattern(json& pattern, const std::string& where, const std::string& file,
                        const std::string& scene, size_t sceneCount) {
  if (!pattern.is_string()) return;  // parseJobJson names the wrong type
  std::string text = pattern.get<std::string>();
  const std::string placeholder = "{scene}";
  if (text.find(placeholder) == std::string::npos) {
    if (sceneCount > 1)
      throw Error(cat(file, ": ", where, ": '", text, "' has no {scene}: in a job of ", sceneCount,
                      " scenes every output pattern needs {scene}, so that each scene writes ",
                      "its own files (e.g. out/{scene}/{camera}.exr)"));
    return;
  }
  for (size_t at = text.find(placeholder); at != std::string::npos;
       at = text.find(placeholder, at + scene.size()))
    text.replace(at, placeholder.size(), scene);
  pattern = text;
}

/// The path a key of a merged entry was written at: in the entry, or at the top level.
std::string writtenAt(const json& entry, const std::string& entryPath, const std::string& key) {
  return entry.contains(key) ? entryPath + "." + key : key;
}

/// {scene} in "output", "preview" and every "outputs" path of one entry's merged job.
void expandScenePatterns(json& merged, const json& entry, const std::string& entryPath,
                         const std::string& file, const std::string& scene, size_t sceneCount) {
  for (const char* key : {"output", "preview"})
    if (merged.contains(key))
      expandScenePattern(merged[key], writtenAt(entry, entryPath, key), file, scene, sceneCount);
  if (!merged.contains("outputs") || !merged["outputs"].is_array()) return;
  json& outputs = merged["outputs"];
  for (size_t k = 0; k < outputs.size(); ++k)
    if (outputs[k].is_object() && outputs[k].contains("path"))
      expandScenePattern(outputs[k]["path"],
                         indexPath(writtenAt(entry, entryPath, "outputs"), k) + ".path", file,
                         scene, sceneCount);
}

/// The directory up to the first placeholder of the first scene's EXR pattern (or first
/// "outputs" path), as written: where summary.json goes.
std::string sharedOutputDirectory(const json& merged, const std::string& baseDir) {
  std::string pattern;
  if (merged.contains("output") && merged["output"].is_string())
    pattern = merged["output"].get<std::string>();
  else if (merged.contains("outputs") && merged["outputs"].is_array() &&
           !merged["outputs"].empty() && merged["outputs"][0].is_object() &&
           merged["outputs"][0].contains("path") && merged["outputs"][0]["path"].is_string())
    pattern = merged["outputs"][0]["path"].get<std::string>();
  return resolve(baseDir, patternDirectory(pattern));
}

/// No two images of different scenes write one file (a per-entry pattern could still).
void checkScenesWriteApart(const std::string& file, const std::vector<Job>& scenes) {
  std::map<std::string, size_t> writer;
  for (size_t s = 0; s < scenes.size(); ++s)
    for (const JobImage& image : scenes[s].images)
      for (const std::string& out : image.files) {
        auto [it, fresh] = writer.emplace(out, s);
        if (!fresh && it->second != s)
          throw Error(cat(file, ": scenes '", scenes[it->second].sceneName, "' and '",
                          scenes[s].sceneName, "' both write '", out,
                          "' (put {scene} in the output patterns)"));
      }
}

/// A job with "scenes": each entry is merged over the other top-level keys (its own keys
/// win) and read as a job of its own, so every check of a one-scene job applies.
JobFile parseScenesJson(const json& root, const std::string& name, const std::string& baseDir) {
  std::vector<std::string> topKeys = jobKeys();
  topKeys.push_back("scenes");
  const Object top(name, "", root, topKeys);
  if (top.has("scene"))
    top.fail("scene", "a job with \"scenes\" gives each scene in its entry, not at the top level");
  const json& entries = top.array("scenes");
  if (entries.empty()) top.fail("scenes", "needs at least one scene");
  if (entries.size() > kMaxJobScenes)
    top.fail("scenes", cat(entries.size(), " scenes; at most ", kMaxJobScenes));
  std::vector<std::string> entryKeys = jobKeys();
  entryKeys.push_back("name");
  JobFile file;
  file.path = name;
  file.multiScene = true;
  std::set<std::string> names;
  size_t imageCount = 0;
  for (size_t k = 0; k < entries.size(); ++k) {
    const std::string entryPath = indexPath("scenes", k);
    const Object entry(name, entryPath, entries[k], entryKeys);
    const std::optional<std::string> sceneName = entry.string("name");
    if (!sceneName) entry.fail(entry.keyPath("name"), "required key is missing");
    checkSceneName(entry, *sceneName);
    if (!names.insert(*sceneName).second)
      entry.fail(entry.keyPath("name"),
                 cat("'", *sceneName, "': a scene of that name already exists"));
    if (!entry.has("scene")) entry.fail(entry.keyPath("scene"), "required key is missing");
    json merged = root;
    merged.erase("scenes");
    std::vector<std::pair<std::string, std::string>> placed;
    for (const auto& item : entries[k].items()) {
      if (item.key() == "name") continue;
      merged[item.key()] = item.value();
      placed.emplace_back(item.key(), entryPath + "." + item.key());
    }
    if (k == 0) file.outputDirectory = sharedOutputDirectory(merged, baseDir);
    expandScenePatterns(merged, entries[k], entryPath, name, *sceneName, entries.size());
    Job job = parseJobJson(merged, name, baseDir, placed);
    // One thread pool serves every scene (and the loads overlapping the renders).
    if (k > 0 && job.threads != file.scenes.front().threads)
      entry.fail(writtenAt(entries[k], entryPath, "performance") + ".threads",
                 cat(job.threads, ": every scene must use the same threads as the first (",
                     file.scenes.front().threads, "): one thread pool serves them all"));
    job.sceneName = *sceneName;
    for (JobImage& image : job.images) {
      image.index += imageCount;
      image.scene = k;
    }
    imageCount += job.images.size();
    if (imageCount > kMaxJobImages)
      entry.fail(entryPath, cat("the scenes so far have ", imageCount, " images; at most ",
                                kMaxJobImages, " in a job"));
    file.scenes.push_back(std::move(job));
  }
  checkScenesWriteApart(name, file.scenes);
  return file;
}

}  // namespace

Job parseJobText(const std::string& text, const std::string& name, const std::string& baseDir) {
  const json root = parseJsonText(text, name);
  if (root.is_object() && root.contains("scenes"))
    throw Error(cat(name, ": scenes: a job of several scenes; read it with readJobFile (",
                    "`aperture batch` does)"));
  return parseJobJson(root, name, baseDir);
}

JobFile readJobFileText(const std::string& text, const std::string& name,
                        const std::string& baseDir) {
  const json root = parseJsonText(text, name);
  if (root.is_object() && root.contains("scenes")) return parseScenesJson(root, name, baseDir);
  JobFile file;
  file.path = name;
  file.scenes.push_back(parseJobJson(root, name, baseDir));
  file.outputDirectory = file.scenes.front().outputDirectory;
  return file;
}

size_t JobFile::imageCount() const {
  size_t n = 0;
  for (const Job& s : scenes) n += s.images.size();
  return n;
}

Job cameraFileJob(const CameraFileBatch& b) {
  if (b.meshes.empty()) throw Error("batch --cameras: give the scene with --mesh MESH");
  if (b.outDir.empty()) throw Error("batch --cameras: give the output folder with --out DIR");
  json meshes = json::array();
  for (const std::string& m : b.meshes) meshes.push_back({{"path", m}});
  json job = {
      {"scene", {{"meshes", meshes}}}, {"cameras", {{"from", b.cameras}}}, {"aovs", b.aovs}};
  if (b.gltfScene) job["scene"]["gltf_scene"] = *b.gltfScene;
  const std::string format = toLowerAscii(b.format);
  const std::string pattern = (fs::path(b.outDir) / ("{image}." + format)).generic_string();
  if (format == "exr") {
    job["output"] = pattern;
  } else {
    if (!datasetFormatOf(pattern))
      throw Error(cat(
          "batch --format: '", b.format, "': unknown format (known: exr ",
          join(datasetExtensions(), " ", [](const std::string& e) { return e.substr(1); }), ")"));
    if (b.aovs.find(',') != std::string::npos || b.aovs == "all")
      throw Error(cat("batch --format ", format, ": writes one AOV per image, --aov names '",
                      b.aovs,
                      "'; give one AOV, or use --format exr, or a job file with \"outputs\" for "
                      "several (docs/batch.md)"));
    job["outputs"] = json::array({{{"aov", b.aovs}, {"path", pattern}}});
  }
  if (b.depthScale) job["depth_scale"] = *b.depthScale;
  if (!b.images.empty()) job["cameras"]["images"] = b.images;
  if (b.spp) job["spp"] = *b.spp;
  if (b.size) job["size"] = *b.size;
  if (b.layers) job["layers"] = *b.layers;
  if (b.deep) job["deep"] = true;
  if (b.preview) job["preview"] = (fs::path(b.outDir) / "{image}.png").generic_string();
  if (b.normalFrame != "world") job["normal_frame"] = b.normalFrame;
  if (b.idCounts) job["id_counts"] = true;
  return parseJobText(job.dump(), "batch --cameras " + b.cameras, "");
}

namespace {

/// A job file's text, after checking it is a regular file of a sane size.
std::string readJobText(const std::string& path) {
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
  return text.str();
}

}  // namespace

Job parseJob(const std::string& path) {
  return parseJobText(readJobText(path), path, fs::path(path).parent_path().string());
}

JobFile readJobFile(const std::string& path) {
  return readJobFileText(readJobText(path), path, fs::path(path).parent_path().string());
}

}  // namespace aperture::app
