#include "apps/cli/camera_flags.h"

#include <cmath>

#include "apps/services/camera_file_params.h"
#include "cameras/registry/registry.h"
#include "core/util/error.h"

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
    const std::string help = describeCameraParam(*spec, defaults);
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
/// The parameters of the one image of a camera file the command line selects (a glTF camera
/// at `gltfSize`).
ParamSet cameraFileParams(const std::string& path, const std::vector<std::string>& images,
                          const CameraFileOptions& options, const GltfImageSize& gltfSize) {
  const CameraFile file = readCameraFile(path, options);
  if (images.size() > 1) throw Error(cat("--image: give one image (got ", images.size(), ")"));
  if (images.empty() && file.images.size() != 1)
    throw Error(cat("--cameras ", path, ": the file has ", file.images.size(),
                    " images; choose one with --image NAME (first: '",
                    file.images.empty() ? "" : file.images.front().name, "')"));
  return imageParamSet(file, *selectImages(file, images, "--image").front(), gltfSize);
}
}  // namespace

ParamSet CameraFlags::given(const CameraFileOptions& fileOptions) const {
  if (!images_.empty() && cameraFile_.empty()) throw Error("--image needs --cameras PATH");
  // A glTF camera has no image size of its own: --size, else the default height.
  GltfImageSize gltfSize;
  gltfSize.defaultHeight = defaults_.height;
  for (const Slot& s : slots_)
    if (std::string(s.spec->name) == "size" && s.option->count() > 0) {
      const glm::ivec2 size = std::get<glm::ivec2>(parseParamText(*s.spec, s.text, "--size"));
      gltfSize.width = size.x;
      gltfSize.height = size.y;
    }
  ParamSet set = cameraFile_.empty()
                     ? ParamSet()
                     : cameraFileParams(cameraFile_, images_, fileOptions, gltfSize);
  for (const Slot& s : slots_)
    if (s.option->count() > 0)
      set.set(*s.spec, parseParamText(*s.spec, s.text, s.spec->flag()), s.spec->flag());
  return set;
}

}  // namespace aperture::app
