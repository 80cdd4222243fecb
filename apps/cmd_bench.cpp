// `aperture bench`: Mrays/s of the frame loop beside the bare-Embree baseline, build time,
// load speed and memory, with the configuration printed beside every number.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "apps/camera_flags.h"
#include "apps/commands.h"
#include "apps/presets.h"
#include "apps/render_options.h"
#include "apps/scene_setup.h"
#include "cameras/registry.h"
#include "core/atomic_file.h"
#include "core/baseline.h"
#include "core/error.h"

namespace aperture::app {

namespace {

struct BenchArgs {
  SceneOptions scene;
  CameraFlags camera;
  RenderOptions render;
  int frames = 10, warmup = 3, builds = 3;
  bool baseline = false, quiet = false;
  std::string sweep, json, preset;
};

/// Median, min, max and coefficient of variation of a sample.
struct Summary {
  double median = 0, min = 0, max = 0, cv = 0;
};
Summary summarize(std::vector<double> v) {
  Summary s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  s.min = v.front();
  s.max = v.back();
  double mean = 0, var = 0;
  for (double x : v) mean += x;
  mean /= double(n);
  for (double x : v) var += (x - mean) * (x - mean);
  s.cv = n > 1 && mean > 0 ? std::sqrt(var / double(n - 1)) / mean : 0;
  return s;
}

nlohmann::json toJson(const Summary& s) {
  return {{"median", s.median}, {"min", s.min}, {"max", s.max}, {"cv", s.cv}};
}

/// Mrays/s of `frames` timed frames after `warmup` untimed ones.
std::vector<double> timeFrames(const Scene& scene, const Camera& camera, const RenderSettings& rs,
                               AovMask aovs, int width, int height, int warmup, int frames) {
  Framebuffer fb(width, height, aovs);
  std::vector<double> mrays;
  for (int f = 0; f < warmup + frames; ++f) {
    const RenderStats st = renderImage(scene, camera, rs, fb);
    if (f >= warmup) mrays.push_back(st.mraysPerSecond());
  }
  return mrays;
}

std::vector<double> timeBaseline(const Scene& scene, const BaselineTracer& base, int warmup,
                                 int frames) {
  std::vector<double> mrays;
  for (int f = 0; f < warmup + frames; ++f) {
    const double s = base.traceFrame(scene);
    if (f >= warmup) mrays.push_back(double(base.rayCount()) / s * 1e-6);
  }
  return mrays;
}

void printSummary(const char* label, const Summary& s, int frames) {
  std::printf("%-28s median %8.2f Mrays/s  (min %.2f, max %.2f, cv %.2f%%, %d frames)\n", label,
              s.median, s.min, s.max, 100 * s.cv, frames);
}

int runBench(const BenchArgs& a) {
  const AovMask aovs = parseAovList(a.render.aovs);
  const ParamSet given = a.camera.given();
  const CameraParams unframed =
      resolveCommandCamera(given, a.camera.defaults(), glm::dvec3(0.0), glm::dvec3(0.0));
  const RenderSettings settings = a.render.settings(unframed.spp);
  if (a.frames < 1 || a.frames > 100000)
    throw Error(cat("--frames ", a.frames, " must be in [1, 100000]"));
  if (a.warmup < 0) throw Error(cat("--warmup ", a.warmup, " must be >= 0"));
  if (a.builds < 1) throw Error(cat("--builds ", a.builds, " must be >= 1"));
  if (!a.sweep.empty() && a.sweep != "packet" && a.sweep != "threads" && a.sweep != "quality" &&
      a.sweep != "aovs")
    throw Error(cat("--sweep: '", a.sweep, "' is not one of packet, threads, quality, aovs"));
  checkMemoryBudget(a.scene, {unframed.width, unframed.height}, aovs);

  ThreadLimit threads(a.render.threads);
  Device device;
  const SceneSpec sceneSpec = a.scene.spec();
  LoadedScene loaded = loadSceneMeshes(sceneSpec, a.quiet);
  const CameraParams params =
      resolveCommandCamera(given, a.camera.defaults(), loaded.worldLo, loaded.worldHi);
  buildLoadedScene(device, loaded, sceneSpec, a.quiet, {params});
  const auto camera = makeCamera(params, loaded.scene->renderOrigin());
  const BuildOptions build = a.scene.buildOptions();

  nlohmann::json j;
  std::string meshNames;
  for (const Mesh& m : loaded.meshes) meshNames += (meshNames.empty() ? "" : ";") + m.name;
  j["config"] = {{"meshes", meshNames},
                 {"triangles", loaded.scene->stats().triangles},
                 {"cull", a.scene.cull},
                 {"culled_triangles", loaded.scene->stats().culledTriangles},
                 {"threads", threads.threads()},
                 {"hardware_threads", std::thread::hardware_concurrency()},
                 {"isa", device.isaName()},
                 {"packet_width", settings.packetWidth},
                 {"tile_size", settings.tileSize},
                 {"bvh_quality", a.scene.quality},
                 {"robust", a.scene.robust},
                 {"compact", a.scene.compact},
                 {"placement", a.scene.worldSpace ? "world-space" : "camera-relative"},
                 {"aovs", aovListString(aovs)},
                 {"camera", params.type},
                 {"width", params.width},
                 {"height", params.height},
                 {"spp", params.spp},
                 {"frames", a.frames},
                 {"warmup", a.warmup}};
  std::printf(
      "config: %s, %zu triangles; %d threads, Embree ISA %s; packet %d, tile %d; BVH %s%s%s; "
      "AOVs %s; %s %dx%d, %d spp\n",
      meshNames.c_str(), loaded.scene->stats().triangles, threads.threads(),
      device.isaName().c_str(), settings.packetWidth, settings.tileSize, a.scene.quality.c_str(),
      a.scene.robust ? " robust" : "", a.scene.compact ? " compact" : "",
      aovListString(aovs).c_str(), params.type.c_str(), params.width, params.height, params.spp);

  // Load and build.
  const double loadMBps = loaded.fileBytes / 1e6 / std::max(loaded.loadSeconds, 1e-9);
  j["load_seconds"] = loaded.loadSeconds;
  j["load_mb_per_s"] = loaded.fileBytes ? loadMBps : 0.0;
  j["file_bytes"] = loaded.fileBytes;
  std::vector<double> buildTimes{loaded.scene->stats().buildSeconds};
  for (int b = 1; b < a.builds; ++b)
    buildTimes.push_back(Scene(device, loaded.objects, build).stats().buildSeconds);
  const Summary buildSummary = summarize(buildTimes);
  const double tris = double(loaded.scene->stats().triangles);
  const double bytes = double(loaded.scene->stats().embreeBytes);
  j["build_seconds"] = toJson(buildSummary);
  j["build_seconds_median"] = buildSummary.median;
  j["embree_bytes"] = bytes;
  j["embree_bytes_per_triangle"] = tris > 0 ? bytes / tris : 0.0;
  if (loaded.cull) {
    j["cull_seconds"] = loaded.cull->seconds;
    j["cull_triangles_before"] = loaded.cull->trianglesBefore;
    j["cull_triangles_kept"] = loaded.cull->trianglesKept;
    j["cull_subset_bytes"] = loaded.cull->subsetBytes;
  }
  std::printf("load: %.1f MB in %.3f s (%.1f MB/s)\n", loaded.fileBytes / 1e6, loaded.loadSeconds,
              loaded.fileBytes ? loadMBps : 0.0);
  std::printf(
      "build: median %.3f s over %d builds (min %.3f, max %.3f); Embree memory %.1f MB "
      "(%.1f bytes/triangle)\n",
      buildSummary.median, a.builds, buildSummary.min, buildSummary.max, bytes / 1e6,
      tris > 0 ? bytes / tris : 0.0);

  // The frame loop, and the baseline right after it in the same run.
  const Summary render = summarize(timeFrames(*loaded.scene, *camera, settings, aovs, params.width,
                                              params.height, a.warmup, a.frames));
  printSummary("render:", render, a.frames);
  j["mrays_per_s"] = toJson(render);
  j["mrays_per_s_median"] = render.median;
  if (a.baseline) {
    BaselineTracer base(*camera, params.width, params.height, settings.tileSize);
    const Summary b = summarize(timeBaseline(*loaded.scene, base, a.warmup, a.frames));
    printSummary("baseline (rtcIntersect16):", b, a.frames);
    std::printf("render / baseline: %.3f\n", render.median / b.median);
    j["baseline_mrays_per_s"] = toJson(b);
    j["baseline_mrays_per_s_median"] = b.median;
    j["render_over_baseline"] = render.median / b.median;
  }

  if (a.sweep == "packet") {
    nlohmann::json rows = nlohmann::json::array();
    for (int w : {1, 4, 8, 16}) {
      RenderSettings s = settings;
      s.packetWidth = w;
      const Summary r = summarize(timeFrames(*loaded.scene, *camera, s, aovs, params.width,
                                             params.height, a.warmup, a.frames));
      printSummary(cat("sweep packet ", w, ":").c_str(), r, a.frames);
      rows.push_back(
          {{"packet_width", w}, {"mrays_per_s", toJson(r)}, {"mrays_per_s_median", r.median}});
    }
    j["sweep_packet"] = rows;
  } else if (a.sweep == "threads") {
    nlohmann::json rows = nlohmann::json::array();
    double single = 0;
    for (int t = 1; t <= threads.threads(); ++t) {
      ThreadLimit limit(t);
      const Summary r = summarize(timeFrames(*loaded.scene, *camera, settings, aovs, params.width,
                                             params.height, a.warmup, a.frames));
      if (t == 1) single = r.median;
      const double efficiency = single > 0 ? r.median / (single * t) : 0;
      printSummary(cat("sweep threads ", t, ":").c_str(), r, a.frames);
      std::printf("%-28s parallel efficiency %.1f%%\n", "", 100 * efficiency);
      rows.push_back({{"threads", t},
                      {"mrays_per_s", toJson(r)},
                      {"mrays_per_s_median", r.median},
                      {"parallel_efficiency", efficiency}});
    }
    j["sweep_threads"] = rows;
  } else if (a.sweep == "quality") {
    nlohmann::json rows = nlohmann::json::array();
    for (BvhQuality q : {BvhQuality::Low, BvhQuality::Medium, BvhQuality::High})
      for (bool robust : {false, true}) {
        BuildOptions bo = build;
        bo.quality = q;
        bo.robust = robust;
        Scene scene(device, loaded.objects, bo);
        const Summary r = summarize(timeFrames(scene, *camera, settings, aovs, params.width,
                                               params.height, a.warmup, a.frames));
        printSummary(cat("sweep ", bvhQualityName(q), robust ? " robust:" : ":").c_str(), r,
                     a.frames);
        std::printf("%-28s build %.3f s, Embree %.1f MB\n", "", scene.stats().buildSeconds,
                    scene.stats().embreeBytes / 1e6);
        rows.push_back({{"bvh_quality", bvhQualityName(q)},
                        {"robust", robust},
                        {"mrays_per_s", toJson(r)},
                        {"mrays_per_s_median", r.median},
                        {"build_seconds", scene.stats().buildSeconds},
                        {"embree_bytes", scene.stats().embreeBytes}});
      }
    j["sweep_quality"] = rows;
  } else if (a.sweep == "aovs") {
    // Interleaved: each round renders one frame of every AOV set, so load from other processes
    // falls on all sets alike.
    const std::vector<std::pair<std::string, AovMask>> sets = {
        {"depth", kAovDepth},
        {"primid", kAovPrimId},
        {"color", kAovColor},
        {"color,depth", kAovColor | kAovDepth},
        {"all", parseAovList("all")}};
    std::vector<Framebuffer> fbs;
    for (const auto& set : sets) fbs.emplace_back(params.width, params.height, set.second);
    std::vector<std::vector<double>> mrays(sets.size());
    for (int f = 0; f < a.warmup + a.frames; ++f)
      for (size_t k = 0; k < sets.size(); ++k) {
        const RenderStats st = renderImage(*loaded.scene, *camera, settings, fbs[k]);
        if (f >= a.warmup) mrays[k].push_back(st.mraysPerSecond());
      }
    nlohmann::json rows = nlohmann::json::object();
    const double depthOnly = summarize(mrays[0]).median;
    for (size_t k = 0; k < sets.size(); ++k) {
      const Summary r = summarize(mrays[k]);
      printSummary(cat("sweep aovs ", sets[k].first, ":").c_str(), r, a.frames);
      std::printf("%-28s %.3f x depth alone\n", "", depthOnly > 0 ? r.median / depthOnly : 0.0);
      rows[sets[k].first] = {{"aovs", aovListString(sets[k].second)},
                             {"mrays_per_s", toJson(r)},
                             {"mrays_per_s_median", r.median},
                             {"relative_to_depth", depthOnly > 0 ? r.median / depthOnly : 0.0}};
    }
    j["sweep_aovs"] = rows;
  }
  if (!a.json.empty()) writeTextAtomically(a.json, j.dump(2) + "\n");
  return 0;
}

}  // namespace

Command addBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* sub = app.add_subcommand(
      "bench", "Measure Mrays/s (median of timed frames after warm-up), build time, load speed");
  addSceneOptions(*sub, args->scene);
  CameraParams benchDefaults;
  benchDefaults.width = 1920;
  benchDefaults.height = 1080;
  args->camera.add(*sub, benchDefaults);
  addRenderOptions(*sub, args->render);
  sub->add_option("--frames", args->frames, "Timed frames")->capture_default_str();
  sub->add_option("--warmup", args->warmup, "Untimed warm-up frames")->capture_default_str();
  sub->add_option("--builds", args->builds, "BVH builds to time (median)")->capture_default_str();
  sub->add_flag("--baseline", args->baseline,
                "Also trace the same rays with bare rtcIntersect16 (no shading, no framebuffer)");
  sub->add_option("--sweep", args->sweep,
                  "Also sweep: packet, threads, quality or aovs (depth alone .. all AOVs, "
                  "interleaved frames)");
  sub->add_option("--json", args->json, "Write every figure to this JSON file");
  sub->add_flag("--quiet", args->quiet, "No log lines on stderr");
  addPresetOption(*sub, args->preset);
  return [args, sub] {
    applyPreset(args->preset, *sub, args->scene, args->camera, nullptr, nullptr);
    return runBench(*args);
  };
}

}  // namespace aperture::app
