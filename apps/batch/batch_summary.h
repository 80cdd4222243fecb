#pragma once
// `aperture batch`: what a run reports when it ends: summary.json (written atomically), the
// table on stdout, the closing lines on stderr and the exit code.
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/batch/batch_result.h"
#include "apps/batch/shard.h"
#include "apps/jobs/job.h"
#include "apps/services/scene_setup.h"

namespace aperture::app {

/// One scene of the run as the summary reports it, kept after the scene itself is released.
struct SceneReport {
  std::string name;                 ///< the "scenes" entry's name; "" for a one-scene job
  std::vector<std::string> meshes;  ///< as loaded (LoadedScene::names), else the job's specs
  bool loaded = false;              ///< false: nothing of it to render, or its load failed
  double loadSeconds = 0;
  BuildStats build;
  size_t instances = 0;
  size_t images = 0;   ///< images of this run (shard) in the scene
  std::string error;   ///< why it could not be loaded or built
  AovMask idAovs = 0;  ///< the job's id AOVs (instance, mesh, material): what `ids` lists
  SceneIds ids;        ///< the names behind those ids, once loaded (LoadedScene::ids)
};

/// What summary.json says of `scene` (as the job lists it, before it is loaded).
SceneReport unloadedSceneReport(const Job& scene);
/// `report` completed from the loaded and built `scene`.
void recordLoadedScene(SceneReport& report, const LoadedScene& scene);

/// The run as a whole, beside its per-image results.
struct BatchRun {
  const JobFile* jobFile = nullptr;
  const Shard* shard = nullptr;
  std::vector<SceneReport> scenes;  ///< one per scene of the job file, in order
  bool resume = false, overlap = true, quiet = false, interrupted = false;
  int threads = 0;
  std::string isa;
  double elapsedSeconds = 0, renderSeconds = 0;
  std::vector<std::string> removedTemporaries;  ///< by --resume
};

/// Per id AOV of `fb` (geomid, instance, mesh, material, then the property AOVs), the number
/// of pixels showing each id.
/// Misses (kInvalidId) are not counted, so each AOV's counts sum to the hit pixels. (A
/// property value of 0xFFFFFFFF, e.g. a label of -1, is indistinguishable from a miss and is
/// not counted either.)
std::map<std::string, std::map<uint32_t, uint64_t>> idCountsOf(const Framebuffer& fb);

/// Where summary.json goes without --summary: the job file's output directory
/// (JobFile::outputDirectory), named summary.json, or summary.shard-K-of-N.json for a shard.
std::string defaultSummaryPath(const JobFile& jobFile, const Shard& shard);

/// summary.json: the run's totals (images_ok, images_failed, ...; BVH, timings) and one entry
/// per image ("images"). A scene whose job asks for id AOVs has "ids": for each of them
/// (instance, mesh, material) the names behind the ids, name k for id k. "frame" in an entry is the
/// frame number along the camera's path. A job with "scenes" adds "scenes" (per scene: name,
/// meshes, load and build figures, images) and "scene" in each image entry; the top-level BVH
/// figures are then sums over scenes.
nlohmann::json batchSummary(const BatchRun& run, const std::vector<ImageResult>& results);

/// Prints the table (camera, frame, status, timings, output) and the totals line on stdout
/// unless run.quiet, writes `summary` to `summaryPath` atomically, reports interruption or
/// failed images on stderr, and returns the exit code: 130 when interrupted, 1 when an image
/// failed or the summary could not be written, else 0.
int reportBatch(const BatchRun& run, const std::vector<ImageResult>& results,
                const nlohmann::json& summary, const std::string& summaryPath);

}  // namespace aperture::app
