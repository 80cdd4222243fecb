// `aperture camera --describe`: the frame, the parameters in every convention and the view
// volume of a camera given with the same flags as render, without loading any mesh.
#include <cstdio>

#include "apps/camera_flags.h"
#include "apps/commands.h"
#include "cameras/describe.h"
#include "cameras/registry.h"
#include "core/error.h"

namespace aperture::app {

namespace {

struct CameraArgs {
  CameraFlags camera;
  bool describe = false, paramsTable = false;
  double nearDist = -1, farDist = -1;
};

int runCamera(const CameraArgs& a) {
  if (a.paramsTable) {
    std::fputs(cameraParamsMarkdown().c_str(), stdout);
    return 0;
  }
  const ParamSet given = a.camera.given();
  if (!given.has("eye"))
    throw Error("camera: --eye is required (there is no scene to frame automatically)");
  if (!a.describe) throw Error("camera: nothing to do (use --describe)");
  const CameraParams params =
      resolveCommandCamera(given, a.camera.defaults(), glm::dvec3(0.0), glm::dvec3(0.0));
  makeCamera(params);  // validates the parameters with the renderer's own errors
  std::fputs(describeCamera(params, a.nearDist, a.farDist).c_str(), stdout);
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
  return [args] { return runCamera(*args); };
}

}  // namespace aperture::app
