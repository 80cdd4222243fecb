// `aperture render`: one frame of a mesh from one camera into a multi-channel EXR.
#include <cstdio>
#include <vector>

#include "apps/camera_flags.h"
#include "apps/commands.h"
#include "apps/outputs.h"
#include "apps/presets.h"
#include "apps/render_options.h"
#include "apps/scene_setup.h"
#include "apps/view.h"
#include "cameras/registry.h"
#include "core/error.h"
#include "core/exr.h"
#include "core/image.h"
#include "core/layers.h"

namespace aperture::app {

namespace {

struct RenderArgs {
  SceneOptions scene;
  CameraFlags camera;
  RenderOptions render;
  std::string out = "out/render.exr", preview, previewRange, compression = "zip", preset;
  bool half = false, quiet = false, cameraSidecar = false;
};

/// --out, --preview and --preview-range, checked before anything is loaded or rendered.
PreviewOptions checkRenderOutputs(const RenderArgs& a, const AovSet& aovs) {
  checkOutputPath("--out", a.out, OutputKind::Exr);
  PreviewOptions preview;
  if (!a.previewRange.empty()) {
    preview.depthRange = parsePreviewRange("--preview-range", a.previewRange);
    if (a.preview.empty())
      throw Error(cat("--preview-range: '", a.previewRange, "' needs --preview"));
  }
  if (a.preview.empty()) return preview;
  checkOutputPath("--preview", a.preview, OutputKind::Preview);
  checkPreviewable("--preview", a.preview, aovs.mask);
  return preview;
}

int runRender(const RenderArgs& a) {
  // Everything that can be checked is checked before loading the mesh.
  const AovSet aovs = a.render.aovSet();
  SceneOptions sceneOptions = a.scene;
  sceneOptions.contextFilter = layersNeedContextFilter(aovs);
  ExrOptions exr;
  exr.compression = parseExrCompression(a.compression);
  exr.halfColor = a.half;
  const ParamSet given = a.camera.given();
  const CameraParams unframed =
      resolveCommandCamera(given, a.camera.defaults(), glm::dvec3(0.0), glm::dvec3(0.0));
  const RenderSettings settings = a.render.settings(unframed.spp);
  checkMemoryBudget(a.scene, {unframed.width, unframed.height}, aovs, a.preview.empty() ? 0 : 4);
  const PreviewOptions preview = checkRenderOutputs(a, aovs);
  if (given.has("eye") || unframed.worldToCamera || unframed.cameraToWorld) makeCamera(unframed);

  ThreadLimit threads(a.render.threads);
  Device device;
  CameraParams params;
  LoadedScene loaded =
      loadSceneForCamera(device, sceneOptions, given, a.camera.defaults(), a.quiet, params);

  const RenderedView view = renderView(*loaded.scene, params, settings, aovs);
  const Framebuffer& fb = view.fb;
  if (!a.quiet)
    std::fprintf(stderr,
                 "aperture: rendered %dx%d, %d spp, AOVs %s: %.3f s, %.1f Mrays/s (%d threads)\n",
                 fb.width, fb.height, settings.spp, aovListString(aovs).c_str(), view.stats.seconds,
                 view.stats.mraysPerSecond(), threads.threads());

  std::vector<std::string> meshNames;
  for (const Mesh& m : loaded.meshes) meshNames.push_back(m.name);
  const ExrMetadata meta =
      viewMetadata(view, meshNames, aovs, a.scene.buildOptions(), a.scene.loadOptions().placement);
  writeViewOutputs(view, meta, exr, a.out, a.preview, preview, a.cameraSidecar);
  if (!a.quiet && !a.preview.empty())
    std::fprintf(stderr, "aperture: wrote %s\n", a.preview.c_str());
  if (!a.quiet) std::fprintf(stderr, "aperture: wrote %s\n", a.out.c_str());
  return 0;
}

}  // namespace

Command addRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand("render", "Render one frame to a multi-channel EXR");
  addSceneOptions(*sub, args->scene);
  args->camera.add(*sub);
  addRenderOptions(*sub, args->render);
  sub->add_option("--out", args->out, "Output EXR path, must end in .exr (written atomically)")
      ->capture_default_str();
  sub->add_option("--preview", args->preview,
                  "Also write an opaque 8-bit preview (.png .jpg .jpeg .tif .tiff .bmp .tga "
                  ".ppm) of color, else depth, normal, primid or geomid; written before the EXR");
  sub->add_option("--preview-range", args->previewRange,
                  "NEAR,FAR: a depth preview maps depth NEAR to white and FAR to black, clamped "
                  "(default: the image's own nearest and farthest depth)");
  sub->add_flag("--half", args->half, "Store color (R G B A) as half; geometry stays float32");
  sub->add_option("--compression", args->compression,
                  "EXR compression: none rle zips zip piz pxr24 b44 b44a dwaa dwab")
      ->capture_default_str();
  sub->add_flag("--camera-sidecar", args->cameraSidecar,
                "Also write the camera as calibrated JSON (K, distortion, world-to-camera in "
                "OpenCV and OpenGL axes) beside --out: NAME.camera.json (perspective and "
                "calibrated cameras)");
  sub->add_flag("--quiet", args->quiet, "No log lines");
  addPresetOption(*sub, args->preset);
  return [args, sub] {
    applyPreset(args->preset, *sub, args->scene, args->camera, &args->half, &args->compression);
    return runRender(*args);
  };
}

}  // namespace aperture::app
