#include "apps/camera_flags.h"

#include <cmath>

#include "apps/camera_files.h"
#include "core/error.h"

namespace aperture::app {

namespace {
/// How --help shows a value: "X,Y,Z", "W,H", "x|y|diagonal".
std::string valueShape(const ParamSpec& spec) {
  switch (spec.kind) {
    case ParamKind::Number:
      return "NUMBER";
    case ParamKind::Integer:
      return "INT";
    case ParamKind::Vec2:
      return "A,B";
    case ParamKind::Vec3:
      return "X,Y,Z";
    case ParamKind::Size:
      return "W,H";
    case ParamKind::Flag:
      return "";
    case ParamKind::Numbers:
      return spec.count == 4 ? "A,B,C,D" : spec.count == 16 ? "16 NUMBERS" : "A,B,...";
    case ParamKind::Choice:
      break;
  }
  const std::vector<const char*> choices = spec.choiceList();
  return choices.empty() ? "NAME" : aperture::join(choices, "|");
}
}  // namespace

void CameraFlags::add(CLI::App& app, const CameraParams& defaults) {
  defaults_ = defaults;
  for (const ParamSpec* spec : allCameraParamSpecs()) {
    slots_.push_back(Slot{spec, nullptr, std::string(), false});
    Slot& slot = slots_.back();
    const std::string help = spec->describeText(defaults);
    if (spec->kind == ParamKind::Flag)
      slot.option = app.add_flag(spec->flag(), slot.present, help);
    else
      slot.option = app.add_option(spec->flag(), slot.text, help)->type_name(valueShape(*spec));
  }
  app.add_option("--cameras", cameraFile_, std::string(kCameraFileHelp) + "; with --image")
      ->type_name("PATH");
  app.add_option("--image", images_, "The image of --cameras whose camera to use")
      ->type_name("NAME");
}

namespace {
/// The parameters of the one image of a camera file the command line selects.
ParamSet cameraFileParams(const std::string& path, const std::vector<std::string>& images) {
  const CameraFile file = readCameraFile(path);
  if (images.size() > 1) throw Error(cat("--image: give one image (got ", images.size(), ")"));
  if (images.empty() && file.images.size() != 1)
    throw Error(cat("--cameras ", path, ": the file has ", file.images.size(),
                    " images; choose one with --image NAME (first: '",
                    file.images.empty() ? "" : file.images.front().name, "')"));
  return imageParamSet(file, *selectImages(file, images, "--image").front());
}
}  // namespace

ParamSet CameraFlags::given() const {
  if (!images_.empty() && cameraFile_.empty()) throw Error("--image needs --cameras PATH");
  ParamSet set = cameraFile_.empty() ? ParamSet() : cameraFileParams(cameraFile_, images_);
  for (const Slot& s : slots_)
    if (s.option->count() > 0)
      set.set(*s.spec, parseParamText(*s.spec, s.text, s.spec->flag()), s.spec->flag());
  return set;
}

CameraParams resolveCommandCamera(const ParamSet& given, const CameraParams& defaults,
                                  const glm::dvec3& lo, const glm::dvec3& hi) {
  CameraParams p = resolveCameraParams(given, defaults);
  if (p.worldToCamera || p.cameraToWorld) return p;  // posed by its matrix
  const glm::dvec3 centre = 0.5 * (lo + hi);
  if (given.has("eye")) {
    if (!p.at && !p.dir) p.at = centre;
    return p;
  }
  // Frame the scene: look at its centre from above-front, far enough for the bounding
  // sphere to fit the vertical field of view.
  const double radius = std::max(0.5 * glm::length(hi - lo), 1e-6);
  const double halfFov = 0.5 * p.fovDeg.value_or(kDefaultFovDeg) * 3.14159265358979323846 / 180.0;
  const glm::dvec3 view =
      p.dir ? glm::normalize(*p.dir) : glm::normalize(glm::dvec3(-0.35, -0.45, -1.0));
  const glm::dvec3 target = p.at.value_or(centre);
  p.eye = target - view * (0.8 * radius / std::sin(halfFov));
  if (!p.dir) p.at = target;
  return p;
}

LoadedScene loadSceneForCamera(const Device& device, const SceneOptions& scene,
                               const ParamSet& given, const CameraParams& defaults, bool quiet,
                               CameraParams& camera) {
  const SceneSpec spec = scene.spec();
  LoadedScene loaded = loadSceneMeshes(spec, quiet);
  camera = resolveCommandCamera(given, defaults, loaded.worldLo, loaded.worldHi);
  buildLoadedScene(device, loaded, spec, quiet, {camera});
  return loaded;
}

}  // namespace aperture::app
