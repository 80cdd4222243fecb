// `aperture render`: one frame of a mesh from one camera into a multi-channel EXR, or one AOV
// into a dataset file (16-bit PNG depth, PFM, NPY, float TIFF) when --out has that extension.
#include <cmath>
#include <cstdio>
#include <vector>

#include "apps/cli/camera_flags.h"
#include "apps/cli/commands.h"
#include "apps/cli/preset_flags.h"
#include "apps/cli/render_flags.h"
#include "apps/cli/scene_flags.h"
#include "apps/services/outputs.h"
#include "apps/services/render_options.h"
#include "apps/services/scene_setup.h"
#include "apps/services/view.h"
#include "cameras/lidar/rolling_shutter.h"
#include "cameras/lidar/trajectory.h"
#include "cameras/registry/registry.h"
#include "core/engine/layers.h"
#include "core/exr/exr.h"
#include "core/io/dataset_image.h"
#include "core/io/image.h"
#include "core/io/image_codec.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

struct RenderArgs {
  SceneOptions scene;
  CameraFlags camera;
  RenderOptions render;
  std::string out = "out/render.exr", preview, previewRange, compression = "zip", preset;
  bool half = false, quiet = false, cameraSidecar = false;
  bool deep = false;  ///< --deep: the layers to <out stem>.deep.exr
  double depthScale = 1000.0;
  double rollingShutter = 0;  ///< --rolling-shutter: seconds between rows' readouts
  std::string trajectory, trajectoryTimes, frameTime;
};

/// --rolling-shutter with --trajectory (and --trajectory-times, --time), read and checked
/// before the mesh loads: the camera wrap renderView applies, or none without the flag.
CameraWrap rollingShutterOf(const RenderArgs& a, int height) {
  if (a.rollingShutter == 0 && a.trajectory.empty()) return {};
  if (!(a.rollingShutter >= 0) || !std::isfinite(a.rollingShutter))
    throw Error(
        cat("--rolling-shutter: ", a.rollingShutter, " is not a readout time in seconds (≥ 0)"));
  if (a.trajectory.empty())
    throw Error("--rolling-shutter: needs --trajectory (the poses the rows are read along)");
  auto trajectory = std::make_shared<Trajectory>(loadTrajectory(a.trajectory, a.trajectoryTimes));
  const int64_t start =
      a.frameTime.empty() ? trajectory->startNs() : parseTimeNs(a.frameTime, "--time");
  const double readout = a.rollingShutter;
  checkRollingShutter(*trajectory, start, readout, height);
  return [trajectory, start, readout, height](std::shared_ptr<const Camera> camera,
                                              const glm::dvec3& renderOrigin) {
    return rollingShutterCamera(std::move(camera), *trajectory, start, readout, height,
                                renderOrigin);
  };
}

/// --out with a dataset extension: the one AOV requested, written alone in that format.
/// Refuses several AOVs, and an AOV the format cannot hold, before anything is rendered.
std::vector<DatasetOutput> datasetOutputsOf(const RenderArgs& a, const AovSet& aovs) {
  const std::optional<DatasetFormat> format = datasetFormatOf(a.out);
  if (!format) return {};
  const std::string names = aovListString(aovs);
  if (names.find(',') != std::string::npos || aovs.layers > 0)
    throw Error(cat("--out: '", a.out, "': a ", datasetFormatName(*format),
                    " file holds one AOV, but the AOVs are ", names,
                    "; give one with --aov (e.g. --aov depth), write them all to an EXR (--out "
                    "NAME.exr), render once per AOV, or use a batch job with \"outputs\" "
                    "(docs/batch.md)"));
  checkDatasetOutput("--out", a.out, names);
  return {{names, a.out}};
}

/// --out, --depth-scale, --preview and --preview-range, checked before anything is loaded or
/// rendered.
PreviewOptions checkRenderOutputs(const RenderArgs& a, const AovSet& aovs) {
  checkOutputPath("--out", a.out, datasetFormatOf(a.out) ? OutputKind::Dataset : OutputKind::Exr);
  checkDepthScale("--depth-scale", a.depthScale);
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
  sceneOptions.aovs = aovs;  // the mesh data and BVH flags the AOVs need (withAovNeeds)
  ExrOptions exr;
  exr.compression = parseExrCompression(a.compression);
  exr.halfColor = a.half;
  checkDeepHasLayers(a.deep, a.render.layers);
  exr.layersInDeepFile = a.deep;
  const ParamSet given = a.camera.given();
  const CameraParams unframed =
      resolveCommandCamera(given, a.camera.defaults(), glm::dvec3(0.0), glm::dvec3(0.0));
  const RenderSettings settings = a.render.settings(unframed.spp);
  const std::vector<DatasetOutput> datasets = datasetOutputsOf(a, aovs);
  const bool imageCodec = writesThroughImageCodec(!a.preview.empty(), {a.out});
  checkMemoryBudget(a.scene, {unframed.width, unframed.height}, aovs, a.preview.empty() ? 0 : 4,
                    imageCodec, {unframed});
  if (imageCodec) aperture::imageCodec();  // a missing plugin fails before the mesh loads
  const PreviewOptions preview = checkRenderOutputs(a, aovs);
  const CameraWrap rollingShutter = rollingShutterOf(a, unframed.height);
  if (given.has("eye") || unframed.sourceCameraFromWorld || unframed.worldFromSourceCamera)
    makeCamera(unframed);

  ThreadLimit threads(a.render.threads);
  const ExrEncodingThreads encoding(threads.threads(), exr.compression);
  Device device;
  CameraParams params;
  LoadedScene loaded =
      loadSceneForCamera(device, sceneOptions, given, a.camera.defaults(), a.quiet, params);

  const RenderedView view = renderView(*loaded.scene, params, settings, aovs, rollingShutter);
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
  DatasetWriteOptions dataset;
  dataset.depthScale = a.depthScale;
  writeViewOutputs(view, meta, exr, datasets.empty() ? a.out : std::string(), a.preview, preview,
                   a.cameraSidecar, datasets, dataset);
  if (!a.quiet && !a.preview.empty())
    std::fprintf(stderr, "aperture: wrote %s\n", a.preview.c_str());
  if (!a.quiet) std::fprintf(stderr, "aperture: wrote %s\n", a.out.c_str());
  return 0;
}

}  // namespace

Command addRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand(
      "render", "Render one frame to a multi-channel EXR (or one AOV to a dataset file)");
  addSceneOptions(*sub, args->scene);
  args->camera.add(*sub);
  addRenderOptions(*sub, args->render);
  addDeepOption(*sub, args->deep);
  sub->add_option("--out", args->out,
                  "Output path, written atomically: .exr holds every AOV; .png (16-bit depth), "
                  ".pfm, .npy, .tif/.tiff hold the one AOV --aov names")
      ->capture_default_str();
  sub->add_option("--depth-scale", args->depthScale,
                  "16-bit PNG --out: value = round(depth * S), 0 for misses and out of range (a "
                  "warning counts them); 1000 = millimetres per metre, 5000 for TUM")
      ->capture_default_str();
  sub->add_option("--preview", args->preview,
                  cat("Also write an opaque 8-bit preview (", join(previewExtensions(), " "),
                      ") of ", previewableAovText(),
                      ", for looking at (--out x.png is the 16-bit depth data); written before "
                      "the EXR"));
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
  sub->add_option("--rolling-shutter", args->rollingShutter,
                  "SECONDS between the readouts of consecutive rows (a rolling shutter): row i "
                  "is read at --time + i*SECONDS and moves with --trajectory since --time; 0 "
                  "renders the global-shutter image bit for bit");
  sub->add_option("--trajectory", args->trajectory,
                  "Poses of the camera's motion: TUM rows (t tx ty tz qx qy qz qw) or KITTI rows "
                  "with --trajectory-times (docs/lidar.md)");
  sub->add_option("--trajectory-times", args->trajectoryTimes,
                  "Times (seconds, one per line) of KITTI --trajectory rows");
  sub->add_option("--time", args->frameTime,
                  "Trajectory time (seconds) of the first row's readout (default: the "
                  "trajectory's first time)");
  sub->add_flag("--quiet", args->quiet, "No log lines");
  addPresetOption(*sub, args->preset);
  return [args, sub] {
    applyPreset(args->preset, *sub, args->scene, args->camera, &args->half, &args->compression);
    return runRender(*args);
  };
}

}  // namespace aperture::app
