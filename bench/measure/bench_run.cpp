#include "bench/measure/bench_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "apps/services/command_camera.h"
#include "bench/measure/baseline.h"
#include "cameras/registry/registry.h"
#include "core/aov/aov_table.h"
#include "core/engine/layers.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/stats.h"
#include "core/util/vector_kernel.h"

namespace aperture::app {

namespace {

nlohmann::json toJson(const SampleSummary& s) {
  return {{"median", s.median}, {"min", s.min}, {"max", s.max}, {"cv", s.cv}};
}

/// Mrays/s of `frames` timed frames after `warmup` untimed ones.
std::vector<double> timeFrames(const Scene& scene, const Camera& camera, const RenderSettings& rs,
                               const AovSet& aovs, int width, int height, int warmup, int frames) {
  Framebuffer fb(width, height, aovs);
  std::vector<double> mrays;
  for (int f = 0; f < warmup + frames; ++f) {
    const RenderStats st = renderImage(scene, camera, rs, fb);
    if (f >= warmup) mrays.push_back(st.mraysPerSecond());
  }
  return mrays;
}

void printSummary(const char* label, const SampleSummary& s, int frames) {
  std::printf("%-28s median %8.2f Mrays/s  (min %.2f, max %.2f, cv %.2f%%, %d frames)\n", label,
              s.median, s.min, s.max, 100 * s.cv, frames);
}

/// Throws Error for a bad --frames, --warmup, --builds or --sweep.
void validateBenchRequest(const BenchRequest& a) {
  if (a.frames < 1 || a.frames > 100000)
    throw Error(cat("--frames ", a.frames, " must be in [1, 100000]"));
  if (a.warmup < 0) throw Error(cat("--warmup ", a.warmup, " must be >= 0"));
  if (a.builds < 1) throw Error(cat("--builds ", a.builds, " must be >= 1"));
  if (!a.sweep.empty() && a.sweep != "packet" && a.sweep != "threads" && a.sweep != "quality" &&
      a.sweep != "aovs")
    throw Error(cat("--sweep: '", a.sweep, "' is not one of packet, threads, quality, aovs"));
  if (a.nullTrace && a.baseline)
    throw Error("--null measures the frame loop without Embree; --baseline traces with it");
  parseBaselineApi(a.baselineApi, "--baseline-api");
  if (a.nullTrace && a.sweep == "quality")
    throw Error("--null traces no BVH: --sweep quality measures nothing there");
}

/// What every measurement of one bench run shares: the loaded scene, its camera and settings.
struct Bench {
  const BenchRequest& args;
  const ThreadLimit& threads;
  const Device& device;
  LoadedScene& loaded;
  AovSet aovs;
  RenderSettings settings;
  BuildOptions build;
  CameraParams params;
  std::unique_ptr<Camera> camera;

  /// Mrays/s of the run's timed frames of `scene` with `rs` and `frameAovs`.
  SampleSummary timeScene(const Scene& scene, const RenderSettings& rs,
                          const AovSet& frameAovs) const {
    return summarize(timeFrames(scene, *camera, rs, frameAovs, params.width, params.height,
                                args.warmup, args.frames));
  }
  SampleSummary time(const RenderSettings& rs) const { return timeScene(*loaded.scene, rs, aovs); }
};

/// The configuration beside every number: in the JSON and on stdout.
void reportConfig(const Bench& b, nlohmann::json& j) {
  const BenchRequest& a = b.args;
  const BuildStats& st = b.loaded.scene->stats();
  const std::string meshNames = join(b.loaded.meshes, ";", [](const Mesh& m) { return m.name; });
  // The mode of the scene actually built, which the frame loop and the baseline both trace.
  const bool robust = b.loaded.scene->options().robust;
  j["config"] = {{"meshes", meshNames},
                 {"triangles", st.triangles},
                 {"cull", a.scene.cull},
                 {"culled_triangles", st.culledTriangles},
                 {"threads", b.threads.threads()},
                 {"hardware_threads", std::thread::hardware_concurrency()},
                 {"isa", b.device.isaName()},
                 {"kernel_isa", kernelIsaName(activeKernelIsa())},
                 {"packet_width", b.settings.packetWidth},
                 {"tile_size", b.settings.tileSize},
                 {"bvh_quality", a.scene.quality},
                 {"robust", robust},
                 {"compact", a.scene.compact},
                 {"placement", a.scene.worldSpace ? "world-space" : "camera-relative"},
                 {"aovs", aovListString(b.aovs)},
                 {"layers", b.aovs.layers},
                 {"layers_method", layerMethodName(defaultLayerMethod())},
                 {"camera", b.params.type},
                 {"width", b.params.width},
                 {"height", b.params.height},
                 {"spp", b.params.spp},
                 {"frames", a.frames},
                 {"warmup", a.warmup},
                 {"null", a.nullTrace},
                 {"scene_box_test", b.settings.sceneBoxTest},
                 {"coverage_mask", b.settings.coverageMask}};
  std::printf(
      "config: %s, %zu triangles; %d threads, Embree ISA %s, kernels %s; packet %d, tile %d; "
      "BVH %s%s%s; "
      "AOVs %s; layers %d (%s); %s %dx%d, %d spp\n",
      meshNames.c_str(), st.triangles, b.threads.threads(), b.device.isaName().c_str(),
      kernelIsaName(activeKernelIsa()), b.settings.packetWidth, b.settings.tileSize,
      a.scene.quality.c_str(), robust ? " robust" : " not robust",
      a.scene.compact ? " compact" : "", aovListString(b.aovs).c_str(), b.aovs.layers,
      layerMethodName(defaultLayerMethod()), b.params.type.c_str(), b.params.width, b.params.height,
      b.params.spp);
  if (a.nullTrace)
    std::printf(
        "null trace: no Embree call; every ray is a fake hit (t 1, normal -dir, geomID 0), so "
        "every requested AOV store runs\n");
}

/// Load speed, and the BVH build time over --builds builds (the first is the run's own).
void measureLoadAndBuild(const Bench& b, nlohmann::json& j) {
  const LoadedScene& loaded = b.loaded;
  const double loadMBps = loaded.fileBytes / 1e6 / std::max(loaded.loadSeconds, 1e-9);
  j["load_seconds"] = loaded.loadSeconds;
  j["load_mb_per_s"] = loaded.fileBytes ? loadMBps : 0.0;
  j["file_bytes"] = loaded.fileBytes;
  std::vector<double> buildTimes{loaded.scene->stats().buildSeconds};
  for (int k = 1; k < b.args.builds; ++k)
    buildTimes.push_back(Scene(b.device, loaded.objects, b.build).stats().buildSeconds);
  const SampleSummary builds = summarize(buildTimes);
  const double tris = double(loaded.scene->stats().triangles);
  const double bytes = double(loaded.scene->stats().embreeBytes);
  j["build_seconds"] = toJson(builds);
  j["build_seconds_median"] = builds.median;
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
      builds.median, b.args.builds, builds.min, builds.max, bytes / 1e6,
      tris > 0 ? bytes / tris : 0.0);
}

/// Seconds to overwrite every channel `fb` holds, rows split over the threads as the frame
/// loop's tiles are: the memory floor of writing those AOVs (no rays, no hits).
double fillFramebufferSeconds(Framebuffer& fb) {
  std::vector<std::pair<char*, size_t>> channels;  // bytes per row
  auto add = [&](auto& v) {
    if (!v.empty())
      channels.emplace_back(reinterpret_cast<char*>(v.data()),
                            v.size() * sizeof(v[0]) / size_t(fb.height));
  };
  for (const AovRow& row : aovTable()) {
    if (!fb.has(Aov(row.bit))) continue;
    if (row.isFloat())
      add(floatPixels(fb, row));
    else
      add(uintPixels(fb, row));
  }
  const auto start = std::chrono::steady_clock::now();
  parallelFor(size_t(fb.height), 8, [&](size_t first, size_t last) {
    for (const auto& [data, rowBytes] : channels)
      std::memset(data + first * rowBytes, 0x7f, (last - first) * rowBytes);
  });
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// --null: the frame loop's own cost, wall time over rays (traced lanes) of each timed frame,
/// and beside it, frame by frame in turn, the memory floor: the time to merely overwrite the
/// requested AOV buffers (fillFramebufferSeconds) over the same rays.
void measureNullTrace(const Bench& b, nlohmann::json& j) {
  Framebuffer fb(b.params.width, b.params.height, b.aovs);
  Framebuffer scratch(b.params.width, b.params.height, b.aovs);
  std::vector<double> nsPerRay, floorNsPerRay;
  uint64_t rays = 0;
  for (int f = 0; f < b.args.warmup + b.args.frames; ++f) {
    const RenderStats st = renderImage(*b.loaded.scene, *b.camera, b.settings, fb);
    const double fill = fillFramebufferSeconds(scratch);
    rays = st.raysTraced;
    if (f < b.args.warmup || rays == 0) continue;
    nsPerRay.push_back(st.seconds / double(rays) * 1e9);
    floorNsPerRay.push_back(fill / double(rays) * 1e9);
  }
  const SampleSummary s = summarize(nsPerRay), floor = summarize(floorNsPerRay);
  std::printf("%-28s median %8.3f ns/ray   (min %.3f, max %.3f, cv %.2f%%, %d frames, %llu rays)\n",
              "null (overhead):", s.median, s.min, s.max, 100 * s.cv, b.args.frames,
              static_cast<unsigned long long>(rays));
  std::printf("%-28s median %8.3f ns/ray   (overwriting the requested AOV buffers only)\n",
              "memory floor:", floor.median);
  j["null_ns_per_ray"] = toJson(s);
  j["null_ns_per_ray_median"] = s.median;
  j["null_rays_per_frame"] = rays;
  j["memory_floor_ns_per_ray"] = toJson(floor);
  j["memory_floor_ns_per_ray_median"] = floor.median;
}

/// --baseline: the frame loop and bare rtcIntersect16 (BaselineTracer) on the same rays through
/// the same scene (same BVH, same robust mode), frame by frame in turn, so drift in the
/// machine's speed hits both alike. The ratio is the median of the per-pair ratios.
void measureAgainstBaseline(const Bench& b, nlohmann::json& j) {
  const BaselineTracer base(*b.camera, b.params.width, b.params.height, b.settings.tileSize,
                            parseBaselineApi(b.args.baselineApi, "--baseline-api"));
  Framebuffer fb(b.params.width, b.params.height, b.aovs);
  std::vector<double> render, bare, ratio;
  RenderStats frame;
  for (int f = 0; f < b.args.warmup + b.args.frames; ++f) {
    frame = renderImage(*b.loaded.scene, *b.camera, b.settings, fb);
    const double r = frame.mraysPerSecond();
    const double seconds = base.traceFrame(*b.loaded.scene);
    if (f < b.args.warmup) continue;
    render.push_back(r);
    bare.push_back(double(base.rayCount()) / seconds * 1e-6);
    ratio.push_back(render.back() / bare.back());
  }
  const SampleSummary renderS = summarize(render), bareS = summarize(bare);
  const SampleSummary ratioS = summarize(ratio);
  const bool robust = b.loaded.scene->options().robust;
  printSummary("render:", renderS, b.args.frames);
  const std::string label =
      cat("baseline (", b.args.baselineApi, robust ? ", robust):" : ", not robust):");
  printSummary(label.c_str(), bareS, b.args.frames);
  std::printf("render / baseline: %.3f (median of %d frame pairs; baseline rays: %s)\n",
              ratioS.median, b.args.frames, base.rayGeneration().c_str());
  const double outside = frame.raysTraced ? double(frame.raysOutsideBox) / frame.raysTraced : 0;
  if (frame.maskCovered >= 0)
    std::printf(
        "misses resolved without Embree: %.1f%% of the frame loop's rays, by the coverage "
        "mask (%.1f%% of the image's blocks covered)\n",
        100 * outside, 100 * frame.maskCovered);
  else
    std::printf("misses resolved without Embree: %.1f%% of the frame loop's rays, by %s\n",
                100 * outside,
                frame.boxTested            ? "the scene-box test"
                : !b.settings.sceneBoxTest ? "nothing (--no-scene-box)"
                                           : "nothing (no coverage mask, and every ray starts "
                                             "inside the scene's box)");
  j["rays_outside_box_fraction"] = outside;
  j["coverage_mask_covered"] = frame.maskCovered;
  j["mrays_per_s"] = toJson(renderS);
  j["mrays_per_s_median"] = renderS.median;
  j["baseline_mrays_per_s"] = toJson(bareS);
  j["baseline_mrays_per_s_median"] = bareS.median;
  j["baseline_robust"] = robust;
  j["baseline_ray_generation"] = base.rayGeneration();
  j["baseline_api"] = b.args.baselineApi;
  j["baseline_rays_per_frame"] = base.rayCount();
  j["render_over_baseline"] = ratioS.median;
  j["render_over_baseline_pairs"] = toJson(ratioS);
}

/// The frame loop, and with --baseline bare rtcIntersect16 beside it (measureAgainstBaseline).
void measureRender(const Bench& b, nlohmann::json& j) {
  if (b.args.nullTrace) return measureNullTrace(b, j);
  if (b.args.baseline) return measureAgainstBaseline(b, j);
  const SampleSummary render = b.time(b.settings);
  printSummary("render:", render, b.args.frames);
  j["mrays_per_s"] = toJson(render);
  j["mrays_per_s_median"] = render.median;
}

nlohmann::json sweepPacketWidths(const Bench& b) {
  nlohmann::json rows = nlohmann::json::array();
  for (int w : {1, 4, 8, 16}) {
    RenderSettings s = b.settings;
    s.packetWidth = w;
    const SampleSummary r = b.time(s);
    printSummary(cat("sweep packet ", w, ":").c_str(), r, b.args.frames);
    rows.push_back(
        {{"packet_width", w}, {"mrays_per_s", toJson(r)}, {"mrays_per_s_median", r.median}});
  }
  return rows;
}

/// 1 .. --threads threads, with the parallel efficiency against one thread.
nlohmann::json sweepThreads(const Bench& b) {
  nlohmann::json rows = nlohmann::json::array();
  double single = 0;
  for (int t = 1; t <= b.threads.threads(); ++t) {
    ThreadLimit limit(t);
    const SampleSummary r = b.time(b.settings);
    if (t == 1) single = r.median;
    const double efficiency = single > 0 ? r.median / (single * t) : 0;
    printSummary(cat("sweep threads ", t, ":").c_str(), r, b.args.frames);
    std::printf("%-28s parallel efficiency %.1f%%\n", "", 100 * efficiency);
    rows.push_back({{"threads", t},
                    {"mrays_per_s", toJson(r)},
                    {"mrays_per_s_median", r.median},
                    {"parallel_efficiency", efficiency}});
  }
  return rows;
}

/// Every BVH quality, plain and robust, each a fresh build.
nlohmann::json sweepBvhQuality(const Bench& b) {
  nlohmann::json rows = nlohmann::json::array();
  for (BvhQuality q : {BvhQuality::Low, BvhQuality::Medium, BvhQuality::High})
    for (bool robust : {false, true}) {
      BuildOptions bo = b.build;
      bo.quality = q;
      bo.robust = robust;
      Scene scene(b.device, b.loaded.objects, bo);
      const SampleSummary r = b.timeScene(scene, b.settings, b.aovs);
      printSummary(cat("sweep ", bvhQualityName(q), robust ? " robust:" : ":").c_str(), r,
                   b.args.frames);
      std::printf("%-28s build %.3f s, Embree %.1f MB\n", "", scene.stats().buildSeconds,
                  scene.stats().embreeBytes / 1e6);
      rows.push_back({{"bvh_quality", bvhQualityName(q)},
                      {"robust", robust},
                      {"mrays_per_s", toJson(r)},
                      {"mrays_per_s_median", r.median},
                      {"build_seconds", scene.stats().buildSeconds},
                      {"embree_bytes", scene.stats().embreeBytes}});
    }
  return rows;
}

/// Mrays/s of each AOV set, timed interleaved: each round renders one frame of every set, so
/// load from other processes falls on all sets alike.
std::vector<std::vector<double>> timeAovSetsInterleaved(
    const Bench& b, const std::vector<std::pair<std::string, AovMask>>& sets) {
  std::vector<Framebuffer> fbs;
  for (const auto& set : sets) fbs.emplace_back(b.params.width, b.params.height, set.second);
  std::vector<std::vector<double>> mrays(sets.size());
  for (int f = 0; f < b.args.warmup + b.args.frames; ++f)
    for (size_t k = 0; k < sets.size(); ++k) {
      const RenderStats st = renderImage(*b.loaded.scene, *b.camera, b.settings, fbs[k]);
      if (f >= b.args.warmup) mrays[k].push_back(st.mraysPerSecond());
    }
  return mrays;
}

/// Depth alone .. all AOVs, each relative to depth alone.
nlohmann::json sweepAovs(const Bench& b) {
  std::vector<std::pair<std::string, AovMask>> sets;
  for (const char* list : {"depth", "primid", "color", "color,depth", "all"})
    sets.emplace_back(list, parseAovList(list));
  const std::vector<std::vector<double>> mrays = timeAovSetsInterleaved(b, sets);
  nlohmann::json rows = nlohmann::json::object();
  const double depthOnly = summarize(mrays[0]).median;
  for (size_t k = 0; k < sets.size(); ++k) {
    const SampleSummary r = summarize(mrays[k]);
    const double relative = depthOnly > 0 ? r.median / depthOnly : 0.0;
    printSummary(cat("sweep aovs ", sets[k].first, ":").c_str(), r, b.args.frames);
    std::printf("%-28s %.3f x depth alone\n", "", relative);
    rows[sets[k].first] = {{"aovs", aovListString(sets[k].second)},
                           {"mrays_per_s", toJson(r)},
                           {"mrays_per_s_median", r.median},
                           {"relative_to_depth", relative}};
  }
  return rows;
}

/// The --sweep the run asked for, if any, under its JSON key.
void runSweep(const Bench& b, nlohmann::json& j) {
  const std::string& sweep = b.args.sweep;
  if (sweep == "packet") j["sweep_packet"] = sweepPacketWidths(b);
  if (sweep == "threads") j["sweep_threads"] = sweepThreads(b);
  if (sweep == "quality") j["sweep_quality"] = sweepBvhQuality(b);
  if (sweep == "aovs") j["sweep_aovs"] = sweepAovs(b);
}

}  // namespace

int runBench(const BenchRequest& a) {
  if (!a.layersMethod.empty()) setLayerMethod(parseLayerMethod(a.layersMethod));
  const AovSet aovs = a.render.aovSet();
  if (!aovs.properties.empty())
    throw Error(cat("AOV '", aovs.properties.front().aovName(), "' is not available in bench"));
  SceneOptions sceneOptions = a.scene;
  sceneOptions.aovs = aovs;
  const ParamSet& given = a.camera;
  const CameraParams unframed =
      resolveCommandCamera(given, a.cameraDefaults, glm::dvec3(0.0), glm::dvec3(0.0));
  RenderSettings settings = a.render.settings(unframed.spp);
  settings.nullTrace = a.nullTrace;
  settings.sceneBoxTest = !a.noSceneBox;
  settings.coverageMask = !a.noCoverageMask;
  validateBenchRequest(a);
  checkMemoryBudget(a.scene, {unframed.width, unframed.height}, aovs, 0, false, {unframed});

  const MemoryEstimate estimate =
      benchMemoryEstimate(sceneOptions, unframed.width, unframed.height, aovs);

  ThreadLimit threads(a.render.threads);
  Device device;
  CameraParams params;
  LoadedScene loaded =
      loadSceneForCamera(device, sceneOptions, given, a.cameraDefaults, a.quiet, params);
  MemoryPeaks peaks;
  peaks.afterBuild = peakResidentBytes();
  auto camera = makeCamera(params, loaded.scene->renderOrigin());
  const Bench bench{
      a,      threads,          device, loaded, aovs, settings, sceneOptions.buildOptions(),
      params, std::move(camera)};

  nlohmann::json j;
  reportConfig(bench, j);
  measureLoadAndBuild(bench, j);
  measureRender(bench, j);
  peaks.beforeBaseline = peakResidentBytes();
  runSweep(bench, j);
  peaks.atEnd = peakResidentBytes();
  j["memory"] = benchMemoryReport(loaded, estimate, peaks);
  if (!a.json.empty()) writeTextAtomically(a.json, j.dump(2) + "\n");
  return 0;
}

}  // namespace aperture::app
