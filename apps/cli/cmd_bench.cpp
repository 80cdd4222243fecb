// `aperture bench`: the flags of a bench run; the measurements are bench/measure/bench_run.h.
#include <memory>
#include <string>

#include "apps/cli/camera_flags.h"
#include "apps/cli/commands.h"
#include "apps/cli/preset_flags.h"
#include "apps/cli/render_flags.h"
#include "apps/cli/scene_flags.h"
#include "bench/measure/bench_run.h"
#include "bench/measure/bench_scaling.h"

namespace aperture::app {

namespace {

/// The flags of `aperture bench`; the camera's become the BenchRequest's parameters.
struct BenchArgs {
  BenchRequest request;
  CameraFlags camera;
};

}  // namespace

Command addBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* sub = app.add_subcommand(
      "bench", "Measure Mrays/s (median of timed frames after warm-up), build time, load speed");
  addSceneOptions(*sub, args->request.scene);
  CameraParams benchDefaults;
  benchDefaults.width = 1920;
  benchDefaults.height = 1080;
  args->camera.add(*sub, benchDefaults);
  addRenderOptions(*sub, args->request.render);
  sub->add_option("--frames", args->request.frames, "Timed frames")->capture_default_str();
  sub->add_option("--warmup", args->request.warmup, "Untimed warm-up frames")
      ->capture_default_str();
  sub->add_option("--builds", args->request.builds, "BVH builds to time (median)")
      ->capture_default_str();
  sub->add_flag("--baseline", args->request.baseline,
                "Also trace the same rays with bare rtcIntersect16 (no shading, no framebuffer)");
  sub->add_option("--baseline-api", args->request.baselineApi,
                  "Embree call of the baseline: packet16 (rtcIntersect16, as the frame loop), "
                  "stream-nm or stream-1m (one coherent stream per tile)")
      ->capture_default_str();
  sub->add_flag("--null", args->request.nullTrace,
                "Measure the frame loop's overhead in ns/ray: rays generated and AOVs written, "
                "every ray a fake hit, no Embree call");
  sub->add_flag("--no-scene-box", args->request.noSceneBox,
                "Call Embree for every ray, also those that miss the scene's bounding box (which "
                "the frame loop otherwise resolves as misses itself): measures what that saves");
  sub->add_flag("--no-coverage-mask", args->request.noCoverageMask,
                "Resolve misses by the scene-box test alone, without the coverage mask of the "
                "blocks that see the scene (pinhole cameras): measures what the mask saves");
  sub->add_option("--sweep", args->request.sweep,
                  "Also sweep: packet, threads, quality or aovs (depth alone .. all AOVs, "
                  "interleaved frames)");
  sub->add_option("--json", args->request.json, "Write every figure to this JSON file");
  // Hidden (no group): picks the layered-hit method to measure, as APERTURE_LAYERS_METHOD.
  sub->add_option("--layers-method", args->request.layersMethod)->group("");
  sub->add_flag("--quiet", args->request.quiet, "No log lines on stderr");
  CLI::Option* scaling = sub->add_flag(
      "--scaling", args->request.scaling,
      "Measure procedural:spheres at each --scaling-sizes, each in a fresh child bench (with "
      "--baseline, one build): load s, build s, peak RSS, Embree bytes, Mrays/s against the "
      "baseline and the --max-memory estimate; a Markdown table on stdout, --json FILE and "
      "FILE.md. With --compact, a second row set with the compact BVH");
  scaling->excludes("--mesh")->excludes("--sweep")->excludes("--null");
  sub->add_option("--scaling-sizes", args->request.scalingSizes,
                  "Triangle counts for --scaling, comma-separated (1e5 or 100000)")
      ->capture_default_str()
      ->needs(scaling);
  addPresetOption(*sub, args->request.preset);
  return [args, sub] {
    applyPreset(args->request.preset, *sub, args->request.scene, args->camera, nullptr, nullptr);
    if (args->request.scaling)
      return runScaling({parseScalingSizes(args->request.scalingSizes), args->request.scene.compact,
                         args->request.json});
    args->request.camera = args->camera.given(CameraFileOptions{args->request.scene.gltfScene});
    args->request.cameraDefaults = args->camera.defaults();
    return runBench(args->request);
  };
}

}  // namespace aperture::app
