#include "apps/batch/batch_summary.h"

#include <cstdio>
#include <filesystem>

#include "apps/services/view.h"
#include "core/aov/aov_table.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

namespace fs = std::filesystem;

nlohmann::json imageEntry(const BatchRun& run, const ImageResult& r) {
  const JobImage& image = *r.image;
  const glm::dvec3& eye = image.params.eye;
  nlohmann::json e = {{"index", image.index},
                      {"camera", image.camera},
                      {"frame", image.frame},
                      {"output", image.output},
                      {"status", imageStatusName(r.status)},
                      {"render_seconds", r.renderSeconds},
                      {"write_seconds", r.writeSeconds},
                      {"rays", r.rays},
                      {"mrays_per_s", r.mrays()},
                      {"eye", {eye.x, eye.y, eye.z}}};
  if (run.jobFile->multiScene) e["scene"] = run.jobFile->scenes[image.scene].sceneName;
  if (!image.preview.empty()) e["preview"] = image.preview;
  e["files"] = image.files;
  if (!r.staleReason.empty()) e["stale"] = r.staleReason;
  if (!r.error.empty()) e["error"] = r.error;
  if (!r.idCounts.empty()) {
    nlohmann::json counts = nlohmann::json::object();
    for (const auto& [aov, perId] : r.idCounts) {
      nlohmann::json ids = nlohmann::json::object();
      for (const auto& [id, pixels] : perId) ids[std::to_string(id)] = pixels;
      counts[aov] = ids;
    }
    e["id_counts"] = counts;
  }
  return e;
}

/// Pixels per id of one UINT channel, misses left out.
std::map<uint32_t, uint64_t> countIds(const std::vector<uint32_t>& values) {
  std::map<uint32_t, uint64_t> counts;
  for (uint32_t id : values)
    if (id != kInvalidId) ++counts[id];
  return counts;
}

/// Labels ("camera frame N") of the images with `status`; outputs for skipped ones.
std::vector<std::string> listed(const std::vector<ImageResult>& results, ImageStatus status) {
  std::vector<std::string> items;
  for (const ImageResult& r : results)
    if (r.status == status)
      items.push_back(status == ImageStatus::Skipped ? r.image->output : imageLabel(*r.image));
  return items;
}

size_t countOf(const std::vector<ImageResult>& results, ImageStatus status) {
  size_t n = 0;
  for (const ImageResult& r : results) n += r.status == status;
  return n;
}

struct Totals {
  uint64_t rays = 0;
  double writeSeconds = 0;
  size_t stale = 0;
};

Totals totalsOf(const std::vector<ImageResult>& results) {
  Totals t;
  for (const ImageResult& r : results) {
    t.rays += r.rays;
    t.writeSeconds += r.writeSeconds;
    t.stale += !r.staleReason.empty();
  }
  return t;
}

/// One scene's mesh and BVH figures (the top-level keys of a one-scene job's summary).
nlohmann::json sceneFigures(const SceneReport& scene) {
  if (!scene.loaded) return {{"meshes", scene.meshes}, {"bvh_builds", 0}};
  nlohmann::json figures = {{"meshes", scene.meshes},
                            {"load_seconds", scene.loadSeconds},
                            {"bvh_builds", 1},
                            {"build_seconds", scene.build.buildSeconds},
                            {"triangles", scene.build.triangles},
                            {"unique_triangles", scene.build.uniqueTriangles},
                            {"instances", scene.instances},
                            {"embree_bytes", scene.build.embreeBytes}};
  if (scene.idAovs) {
    nlohmann::json ids = nlohmann::json::object();
    if (scene.idAovs & kAovInstanceId) ids["instance"] = scene.ids.instance;
    if (scene.idAovs & kAovMeshId) ids["mesh"] = scene.ids.mesh;
    if (scene.idAovs & kAovMaterialId) ids["material"] = scene.ids.material;
    figures["ids"] = ids;
  }
  return figures;
}

/// A job with "scenes": each scene's figures, and load, build and BVH counts summed.
nlohmann::json scenesSummary(const BatchRun& run) {
  nlohmann::json scenes = nlohmann::json::array();
  size_t builds = 0;
  double loadSeconds = 0, buildSeconds = 0;
  for (const SceneReport& r : run.scenes) {
    nlohmann::json s = sceneFigures(r);
    s["name"] = r.name;
    s["images"] = r.images;
    if (!r.error.empty()) s["error"] = r.error;
    scenes.push_back(s);
    builds += r.loaded;
    loadSeconds += r.loadSeconds;
    buildSeconds += r.build.buildSeconds;
  }
  return {{"scene_count", run.scenes.size()},
          {"bvh_builds", builds},
          {"load_seconds", loadSeconds},
          {"build_seconds", buildSeconds},
          {"scenes", scenes}};
}

nlohmann::json sceneSummary(const BatchRun& run) {
  return run.jobFile->multiScene ? scenesSummary(run) : sceneFigures(run.scenes.front());
}

/// "scene/camera" in a job with "scenes", else the camera's name.
std::string tableName(const BatchRun& run, const JobImage& image) {
  if (!run.jobFile->multiScene) return image.camera;
  return run.jobFile->scenes[image.scene].sceneName + "/" + image.camera;
}

void printTable(const BatchRun& run, const std::vector<ImageResult>& results) {
  std::printf("%-20s %7s  %-11s %9s %8s %9s  %s\n", "camera", "frame", "status", "render s",
              "write s", "Mrays/s", "output");
  for (const ImageResult& r : results)
    std::printf("%-20s %7d  %-11s %9.3f %8.3f %9.1f  %s\n", tableName(run, *r.image).c_str(),
                r.image->frame, imageStatusName(r.status), r.renderSeconds, r.writeSeconds,
                r.mrays(), r.image->output.c_str());
}

void printTotals(const BatchRun& run, const std::vector<ImageResult>& results) {
  const Totals t = totalsOf(results);
  char bvh[96] = "nothing to render, nothing loaded";
  size_t builds = 0;
  double buildSeconds = 0;
  for (const SceneReport& s : run.scenes) {
    builds += s.loaded;
    buildSeconds += s.build.buildSeconds;
  }
  if (builds == 1)
    std::snprintf(bvh, sizeof bvh, "BVH built once in %.3f s", buildSeconds);
  else if (builds > 1)
    std::snprintf(bvh, sizeof bvh, "%zu BVHs built in %.3f s, loads overlapping renders", builds,
                  buildSeconds);
  std::printf(
      "%zu images ok, %zu failed, %zu skipped, %zu interrupted; %.3f s elapsed (render %.3f s, "
      "write %.3f s%s), %.1f Mrays/s; %s\n",
      countOf(results, ImageStatus::Ok), countOf(results, ImageStatus::Failed),
      countOf(results, ImageStatus::Skipped), countOf(results, ImageStatus::Interrupted),
      run.elapsedSeconds, run.renderSeconds, t.writeSeconds, run.overlap ? ", overlapped" : "",
      run.elapsedSeconds > 0 ? double(t.rays) / run.elapsedSeconds * 1e-6 : 0.0, bvh);
}

/// Writes the summary; false (after saying why on stderr) when it cannot be written.
bool writeSummary(const nlohmann::json& summary, const std::string& path, bool quiet) {
  try {
    ensureParentDirectory(path, "--summary");
    writeTextAtomically(path, summary.dump(2) + "\n");
    if (!quiet) std::fprintf(stderr, "aperture: wrote %s\n", path.c_str());
    return true;
  } catch (const Error& e) {
    std::fprintf(stderr, "aperture: error: %s\n", e.what());
    return false;
  }
}

}  // namespace

std::map<std::string, std::map<uint32_t, uint64_t>> idCountsOf(const Framebuffer& fb) {
  std::map<std::string, std::map<uint32_t, uint64_t>> counts;
  if (fb.has(kAovGeomId)) counts["geomid"] = countIds(fb.geomId);
  // The scene-wide ids (ObjectIds), by their rows' names ("instance", "mesh", "material").
  for (const AovRow& row : aovTable())
    if ((row.bit & (kAovInstanceId | kAovMeshId | kAovMaterialId)) && fb.has(Aov(row.bit)) &&
        row.u32)
      counts[row.name] = countIds(fb.*row.u32);
  for (const PropertyChannel& p : fb.properties) counts[p.property.aovName()] = countIds(p.values);
  return counts;
}

SceneReport unloadedSceneReport(const Job& scene) {
  SceneReport r;
  r.name = scene.sceneName;
  for (const MeshPlacement& m : scene.meshes) r.meshes.push_back(m.spec);
  r.idAovs = scene.aovs.mask & (kAovInstanceId | kAovMeshId | kAovMaterialId);
  return r;
}

void recordLoadedScene(SceneReport& report, const LoadedScene& scene) {
  report.meshes = scene.names;
  report.loaded = true;
  report.loadSeconds = scene.loadSeconds;
  report.build = scene.scene->stats();
  report.instances = scene.scene->instanceCount();
  report.ids = scene.ids;
}

std::string defaultSummaryPath(const JobFile& jobFile, const Shard& shard) {
  const std::string name =
      shard.n > 1 ? cat("summary.shard-", shard.k, "-of-", shard.n, ".json") : "summary.json";
  return (fs::path(jobFile.outputDirectory) / name).lexically_normal().string();
}

nlohmann::json batchSummary(const BatchRun& run, const std::vector<ImageResult>& results) {
  // Size, spp and AOVs are the first scene's (shared unless an entry of "scenes" overrides them).
  const Job& job = run.jobFile->scenes.front();
  const Totals t = totalsOf(results);
  nlohmann::json images = nlohmann::json::array();
  for (const ImageResult& r : results) images.push_back(imageEntry(run, r));
  nlohmann::json s = {
      {"job", fs::absolute(run.jobFile->path).lexically_normal().string()},
      {"aperture_version", APERTURE_VERSION},
      {"shard", {{"k", run.shard->k}, {"n", run.shard->n}, {"from", run.shard->origin}}},
      {"resume", run.resume},
      {"overlap_writes", run.overlap},
      {"images_in_job", run.jobFile->imageCount()},
      {"images_in_shard", results.size()},
      {"images_ok", countOf(results, ImageStatus::Ok)},
      {"images_failed", countOf(results, ImageStatus::Failed)},
      {"images_skipped", countOf(results, ImageStatus::Skipped)},
      {"images_interrupted", countOf(results, ImageStatus::Interrupted)},
      {"images_stale", t.stale},
      {"failed", listed(results, ImageStatus::Failed)},
      {"skipped", listed(results, ImageStatus::Skipped)},
      {"interrupted", listed(results, ImageStatus::Interrupted)},
      {"stale_temporaries_removed", run.removedTemporaries},
      {"threads", run.threads},
      {"isa", run.isa},
      {"width", job.width},
      {"height", job.height},
      {"spp", job.render.spp},
      {"aovs", aovListString(job.aovs)},
      {"elapsed_seconds", run.elapsedSeconds},
      {"render_seconds", run.renderSeconds},
      {"write_seconds", t.writeSeconds},
      {"rays", t.rays},
      {"mrays_per_s", run.elapsedSeconds > 0 ? double(t.rays) / run.elapsedSeconds * 1e-6 : 0.0}};
  s.update(sceneSummary(run));
  s["images"] = images;
  return s;
}

int reportBatch(const BatchRun& run, const std::vector<ImageResult>& results,
                const nlohmann::json& summary, const std::string& summaryPath) {
  if (!run.quiet) {
    printTable(run, results);
    printTotals(run, results);
  }
  const bool written = writeSummary(summary, summaryPath, run.quiet);
  const std::vector<std::string> failed = listed(results, ImageStatus::Failed);
  if (run.interrupted) {
    std::fprintf(stderr, "aperture: interrupted: %zu images written, %zu not rendered\n",
                 countOf(results, ImageStatus::Ok), countOf(results, ImageStatus::Interrupted));
    return 130;
  }
  if (!failed.empty()) {
    const std::string list = join(failed, ", ");
    std::fprintf(stderr, "aperture: %zu of %zu images failed: %s\n", failed.size(), results.size(),
                 list.c_str());
    return 1;
  }
  return written ? 0 : 1;
}

}  // namespace aperture::app
