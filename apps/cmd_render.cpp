// `aperture render`: one frame of a mesh from one camera into a multi-channel EXR.
#include <cstdio>
#include <vector>

#include "apps/commands.h"
#include "apps/options.h"
#include "apps/outputs.h"
#include "apps/view.h"
#include "cameras/registry.h"
#include "core/error.h"
#include "core/exr.h"
#include "core/image.h"

namespace aperture::app {

namespace {

struct RenderArgs {
  SceneOptions scene;
  CameraOptions camera;
  RenderOptions render;
  std::string out = "out/render.exr", preview, previewRange, compression = "zip", preset;
  bool half = false, quiet = false;
};

/// --out, --preview and --preview-range, checked before anything is loaded or rendered.
PreviewOptions checkRenderOutputs(const RenderArgs& a, AovMask aovs) {
  checkOutputPath("--out", a.out, OutputKind::Exr);
  PreviewOptions preview;
  if (!a.previewRange.empty()) {
    preview.depthRange = parsePreviewRange("--preview-range", a.previewRange);
    if (a.preview.empty())
      throw Error(cat("--preview-range: '", a.previewRange, "' needs --preview"));
  }
  if (a.preview.empty()) return preview;
  checkOutputPath("--preview", a.preview, OutputKind::Preview);
  checkPreviewable("--preview", a.preview, aovs);
  return preview;
}

int runRender(const RenderArgs& a) {
  // Everything that can be checked is checked before loading the mesh.
  const AovMask aovs = parseAovList(a.render.aovs);
  ExrOptions exr;
  exr.compression = parseExrCompression(a.compression);
  exr.halfColor = a.half;
  const RenderSettings settings = a.render.settings(a.camera.spp);
  const glm::ivec2 size = parseImageSize(a.camera.size);
  checkMemoryBudget(a.scene, size, aovs, a.preview.empty() ? 0 : 4);
  const PreviewOptions preview = checkRenderOutputs(a, aovs);
  if (!a.camera.eye.empty()) makeCamera(a.camera.toParams(glm::dvec3(0.0), glm::dvec3(0.0)));

  ThreadLimit threads(a.render.threads);
  Device device;
  LoadedScene loaded = loadSceneMeshes(a.scene, a.quiet);
  const CameraParams params = a.camera.toParams(loaded.worldLo, loaded.worldHi);
  buildLoadedScene(device, loaded, a.scene, a.quiet, {params});

  const RenderedView view = renderView(*loaded.scene, params, settings, aovs);
  const Framebuffer& fb = view.fb;
  if (!a.quiet)
    std::fprintf(stderr,
                 "aperture: rendered %dx%d, %d spp, AOVs %s: %.3f s, %.1f Mrays/s (%d threads)\n",
                 fb.width, fb.height, settings.spp, aovListString(aovs).c_str(), view.stats.seconds,
                 view.stats.mraysPerSecond(), threads.threads());

  std::vector<std::string> meshNames;
  for (const Mesh& m : loaded.meshes) meshNames.push_back(m.name);
  const ExrMetadata meta = viewMetadata(view, meshNames, aovs, a.scene.buildOptions().quality,
                                        a.scene.loadOptions().placement);
  writeViewOutputs(view, meta, exr, a.out, a.preview, preview);
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
  addCameraOptions(*sub, args->camera);
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
  sub->add_flag("--quiet", args->quiet, "No log lines");
  addPresetOption(*sub, args->preset);
  return [args, sub] {
    applyPreset(args->preset, *sub, args->scene, args->camera, &args->half, &args->compression);
    return runRender(*args);
  };
}

}  // namespace aperture::app
