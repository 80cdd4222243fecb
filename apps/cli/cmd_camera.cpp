// `aperture camera --describe`: the frame, the parameters in every convention and the view
// volume of a camera given with the same flags as render, without loading any mesh;
// `--export`: the camera as a calibrated camera file.
#include <algorithm>
#include <cstdio>

#include "apps/cli/camera_flags.h"
#include "apps/cli/commands.h"
#include "cameras/files/camera_file.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/describe.h"
#include "cameras/registry/registry.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture::app {

namespace {

struct CameraArgs {
  CameraFlags camera;
  bool describe = false, paramsTable = false;
  double nearDist = -1, farDist = -1;
  std::string exportFormat, out, exportImage = "aperture.png";
};

/// --export colmap|nerf|opencv: the camera as a calibrated camera file of one image.
void exportCamera(const CameraArgs& a, const CameraParams& params) {
  static const std::vector<std::string> formats = {"colmap", "nerf", "opencv"};
  if (std::find(formats.begin(), formats.end(), a.exportFormat) == formats.end())
    throw Error(cat("--export: '", a.exportFormat, "' is not one of ", join(formats, ", "),
                    didYouMean(a.exportFormat, formats)));
  if (a.out.empty())
    throw Error(cat("--export ", a.exportFormat, " needs --out (",
                    a.exportFormat == "colmap" ? "a folder" : "a .json file", ")"));
  const std::optional<CalibratedView> view = calibratedViewOf(params);
  if (!view)
    throw Error(cat("--export: a '", params.type,
                    "' camera has no calibrated form (perspective and calibrated cameras have)"));
  CameraFile file;
  file.path = a.out;
  file.sensors = {view->sensor};
  file.sensorIds = {"1"};
  file.images = {{a.exportImage, 0, view->cvCameraFromWorld}};
  if (a.exportFormat == "colmap") writeColmapText(file, a.out);
  if (a.exportFormat == "nerf") writeNerfstudioJson(file, a.out);
  if (a.exportFormat == "opencv") writeOpenCVJson(file, a.out);
  std::fprintf(stderr, "aperture: wrote %s (%s, image '%s')\n", a.out.c_str(),
               a.exportFormat.c_str(), a.exportImage.c_str());
}

int runCamera(const CameraArgs& a) {
  if (a.paramsTable) {
    std::fputs(cameraParamsMarkdown().c_str(), stdout);
    return 0;
  }
  const ParamSet given = a.camera.given();
  if (!given.has("eye") && !given.has("world_to_camera") && !given.has("camera_to_world"))
    throw Error(
        "camera: --eye (or a pose matrix, or --cameras) is required (there is no scene to frame "
        "automatically)");
  if (!a.describe && a.exportFormat.empty())
    throw Error("camera: nothing to do (use --describe or --export)");
  const CameraParams params =
      resolveCommandCamera(given, a.camera.defaults(), glm::dvec3(0.0), glm::dvec3(0.0));
  makeCamera(params);  // validates the parameters with the renderer's own errors
  if (a.describe) std::fputs(describeCamera(params, a.nearDist, a.farDist).c_str(), stdout);
  if (!a.exportFormat.empty()) exportCamera(a, params);
  return 0;
}

}  // namespace

Command addCameraCommand(CLI::App& app) {
  auto args = std::make_shared<CameraArgs>();
  CLI::App* sub = app.add_subcommand(
      "camera", "Describe a camera: frame, parameters in every convention, view volume");
  args->camera.add(*sub);
  sub->add_flag("--describe", args->describe, "Print the description");
  sub->add_flag("--params-table", args->paramsTable,
                "Print every camera parameter as a Markdown table (docs/cameras.md)");
  sub->add_option("--near", args->nearDist,
                  "Near distance of the printed view volume (scene units)");
  sub->add_option("--far", args->farDist, "Far distance of the printed view volume (scene units)");
  sub->add_option("--export", args->exportFormat,
                  "Write the camera as a calibrated camera file: colmap (a folder of text "
                  "files), nerf (nerfstudio transforms.json) or opencv (JSON), to --out")
      ->type_name("colmap|nerf|opencv");
  sub->add_option("--out", args->out, "Where --export writes");
  sub->add_option("--export-image", args->exportImage, "The image name --export writes")
      ->capture_default_str();
  return [args] { return runCamera(*args); };
}

}  // namespace aperture::app
