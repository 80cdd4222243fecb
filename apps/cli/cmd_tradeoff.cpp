// `aperture tradeoff`: what each speed knob costs in accuracy, on one scene and camera.
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "apps/cli/camera_flags.h"
#include "apps/cli/commands.h"
#include "apps/cli/render_flags.h"
#include "apps/cli/scene_flags.h"
#include "apps/services/render_options.h"
#include "apps/services/scene_setup.h"
#include "bench/measure/tradeoff.h"
#include "cameras/registry/registry.h"
#include "core/io/atomic_file.h"
#include "core/io/image_codec.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

namespace fs = std::filesystem;

struct TradeoffArgs {
  SceneOptions scene;
  CameraFlags camera;
  RenderOptions render;
  std::string outDir = "out/tradeoff", name = "tradeoff", compression = "zip";
  int referenceSpp = 0, frames = 3, warmup = 1, writes = 3;
  bool half = false, quick = false, noCombinations = false, quiet = false;
};

/// The study's settings from the flags (the camera is set apart, once the scene is known).
TradeoffConfig tradeoffConfig(const TradeoffArgs& a) {
  TradeoffConfig c;
  c.scene = a.scene;
  c.base =
      a.render.settings(resolveCommandCamera(a.camera.given(CameraFileOptions{a.scene.gltfScene}),
                                             a.camera.defaults(), glm::dvec3(0.0), glm::dvec3(0.0))
                            .spp);
  c.baseExr.compression = parseExrCompression(a.compression);
  c.baseExr.halfColor = a.half;
  c.quick = a.quick;
  c.combinations = !a.noCombinations;
  c.referenceSpp = a.referenceSpp != 0 ? a.referenceSpp : a.quick ? 16 : 256;
  c.frames = a.frames;
  c.warmup = a.warmup;
  c.writes = a.writes;
  c.quiet = a.quiet;
  if (a.quick) {
    // A smoke run: every knob, fewer values, one timed frame, a 16-spp reference unless given.
    c.frames = 1;
    c.warmup = 0;
    c.writes = 1;
  }
  if (a.name.empty() || a.name.find('/') != std::string::npos)
    throw Error(cat("--name: '", a.name, "' must be a non-empty file name stem"));
  return c;
}

/// The camera from the flags, framing the scene's bounds from a camera-relative load (the
/// study loads its own meshes); a bad camera fails here, before the study starts.
CameraParams framedCamera(const TradeoffArgs& a) {
  glm::dvec3 lo(0.0), hi(0.0);
  {
    Device device;
    SceneOptions o = a.scene;
    o.worldSpace = false;
    const LoadedScene s = loadScene(device, o.spec(), true);
    lo = s.worldLo;
    hi = s.worldHi;
  }
  const CameraParams params = resolveCommandCamera(
      a.camera.given(CameraFileOptions{a.scene.gltfScene}), a.camera.defaults(), lo, hi);
  makeCamera(params);
  return params;
}

/// Runs the study with its EXR files in a temporary directory under `outDir`, removed after.
std::vector<TradeoffRow> runWithTempDir(TradeoffConfig& c, const std::string& outDir) {
  fs::create_directories(outDir);
  c.tempDir = (fs::path(outDir) / cat(".exr-tmp-", getpid())).string();
  std::vector<TradeoffRow> rows;
  try {
    rows = runTradeoff(c);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(c.tempDir, ec);
    throw;
  }
  std::error_code ec;
  fs::remove_all(c.tempDir, ec);
  return rows;
}

/// NAME.csv and NAME.md in --out-dir, and the Markdown table on stdout.
void writeReports(const TradeoffArgs& a, const TradeoffConfig& c, int threads,
                  const std::vector<TradeoffRow>& rows) {
  const std::string csv = (fs::path(a.outDir) / (a.name + ".csv")).string();
  const std::string md = (fs::path(a.outDir) / (a.name + ".md")).string();
  writeTextAtomically(csv, tradeoffCsv(rows));
  const std::string title =
      cat(a.name, ": ", c.camera.type, " ", c.camera.width, "x", c.camera.height, ", reference ",
          c.referenceSpp, " spp (robust, high, camera-relative); ", c.frames,
          " timed frames after ", c.warmup, " warm-up, ", threads, " threads");
  writeTextAtomically(md, tradeoffMarkdown(rows, title));
  if (!a.quiet) std::fprintf(stderr, "aperture: wrote %s and %s\n", csv.c_str(), md.c_str());
  std::printf("%s", tradeoffMarkdown(rows, title).c_str());
}

int runTradeoff(const TradeoffArgs& a) {
  TradeoffConfig c = tradeoffConfig(a);
  imageCodec();  // it compares images: a missing plugin fails before the first render
  ThreadLimit threads(a.render.threads);
  c.encodeThreads = threads.threads();
  c.camera = framedCamera(a);
  const std::vector<TradeoffRow> rows = runWithTempDir(c, a.outDir);
  writeReports(a, c, threads.threads(), rows);
  return 0;
}

}  // namespace

Command addTradeoffCommand(CLI::App& app) {
  auto args = std::make_shared<TradeoffArgs>();
  CLI::App* sub = app.add_subcommand(
      "tradeoff",
      "Sweep the speed knobs one at a time (BVH quality/robust/compact, packet, spp, placement, "
      "EXR half/compression, tile) and measure each against a reference: CSV + Markdown");
  addSceneOptions(*sub, args->scene);
  CameraParams studyDefaults;
  studyDefaults.width = 480;
  studyDefaults.height = 270;
  args->camera.add(*sub, studyDefaults);
  addRenderOptions(*sub, args->render);
  sub->add_option("--reference-spp", args->referenceSpp,
                  "Samples per pixel of the reference (robust, high quality, camera-relative); "
                  "default 256, 16 with --quick");
  sub->add_option("--out-dir", args->outDir, "Directory for NAME.csv and NAME.md")
      ->capture_default_str();
  sub->add_option("--name", args->name, "File name stem and table title")->capture_default_str();
  sub->add_option("--frames", args->frames, "Timed frames per setting (median)")
      ->capture_default_str();
  sub->add_option("--warmup", args->warmup, "Untimed frames per setting")->capture_default_str();
  sub->add_option("--writes", args->writes, "Timed EXR writes per EXR setting (median)")
      ->capture_default_str();
  sub->add_flag("--half", args->half, "Base setting: color as half");
  sub->add_option("--compression", args->compression, "Base setting: EXR compression")
      ->capture_default_str();
  sub->add_flag("--quick", args->quick,
                "Smoke run: every knob with fewer values, 1 timed frame, no warm-up");
  sub->add_flag("--no-combinations", args->noCombinations,
                "Leave out the spp x BVH-quality combinations");
  sub->add_flag("--quiet", args->quiet, "No log lines on stderr");
  return [args] { return runTradeoff(*args); };
}

}  // namespace aperture::app
