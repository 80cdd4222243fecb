// `aperture batch`: many views of one scene from a job file; the BVH is built once, images
// render with all cores while a writer thread encodes the previous image. A job of several
// scenes ("scenes") renders scene k while scene k+1 loads and builds (apps/batch/scene_pipeline.h).
// This file holds the command line and the run's steps; the pieces live in batch_*.h, shard.h,
// resume.h and merge_summaries.h.
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "apps/batch/batch_progress.h"
#include "apps/batch/batch_result.h"
#include "apps/batch/batch_summary.h"
#include "apps/batch/batch_writer.h"
#include "apps/batch/merge_summaries.h"
#include "apps/batch/resume.h"
#include "apps/batch/scene_pipeline.h"
#include "apps/batch/shard.h"
#include "apps/cli/commands.h"
#include "apps/cli/render_flags.h"
#include "apps/jobs/job.h"
#include "apps/jobs/job_outputs.h"
#include "apps/services/camera_file_params.h"
#include "apps/services/limits.h"
#include "apps/services/render_options.h"
#include "apps/services/scene_setup.h"
#include "apps/services/view.h"
#include "cameras/files/camera_file.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/io/atomic_file.h"
#include "core/io/image_codec.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

struct BatchArgs {
  std::vector<std::string> files;  ///< the job, or with --merge-summaries the summaries
  CameraFileBatch cameraFile;      ///< the one-line form: --mesh, --cameras, --out, --aov
  std::string shard, summary, maxMemory, mergeOut;
  bool resume = false, quiet = false, dryRun = false, noOverlap = false;
};

// SIGINT sets this; the image loop checks it between images. SA_RESETHAND makes a second
// Ctrl-C kill at once (temporary files may then remain, but never a partial final file).
volatile std::sig_atomic_t gInterrupted = 0;
extern "C" void onSigint(int) { gInterrupted = 1; }

class SigintGuard {
 public:
  SigintGuard() {
    struct sigaction sa {};
    sa.sa_handler = onSigint;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &previous_);
  }
  ~SigintGuard() { sigaction(SIGINT, &previous_, nullptr); }

 private:
  struct sigaction previous_ {};
};

/// What this run does: the job file (its scenes), its shard and one result per image of the
/// shard, in job order (scene by scene).
struct BatchPlan {
  JobFile jobs;
  Shard shard;
  std::vector<ImageResult> results;
  size_t toRender = 0;
  std::vector<std::string> removedTemporaries;
};

/// The results of one scene: plan.results[first, last).
struct SceneImages {
  size_t scene = 0, first = 0, last = 0;
  size_t toRender = 0;
};

/// The mesh specs, largest image and per-pixel bytes of one scene, for the memory estimate.
struct SceneFootprint {
  std::vector<std::string> specs;
  uint64_t pixels = 0, bytesPerPixel = 0;
};

/// Whether any scene of the job file writes through the image codec.
bool anyWritesThroughImageCodec(const JobFile& jobs) {
  return std::any_of(jobs.scenes.begin(), jobs.scenes.end(), [](const Job& job) {
    std::vector<std::string> patterns;
    for (const JobDatasetOutput& d : job.datasets) patterns.push_back(d.pattern);
    return writesThroughImageCodec(!job.previewPattern.empty(), patterns);
  });
}

/// Pixels of the job's largest image.
uint64_t largestImagePixels(const Job& job) {
  uint64_t pixels = 0;
  for (const JobImage& image : job.images)
    pixels = std::max(pixels, uint64_t(image.params.width) * uint64_t(image.params.height));
  return pixels;
}

/// The writer threads of the job's images (writerThreadsFor over its largest framebuffer, for
/// the batch's `threads`); 0 with --no-overlap, where each image is written inline.
int writersOf(const Job& job, int threads, bool overlap) {
  if (!overlap) return 0;
  return writerThreadsFor(threads, largestImagePixels(job) * framebufferBytesPerPixel(job.aovs));
}

SceneFootprint footprintOf(const Job& job, int writers) {
  SceneFootprint f;
  for (const MeshPlacement& m : job.meshes)
    if (std::find(f.specs.begin(), f.specs.end(), m.spec) == f.specs.end())
      f.specs.push_back(m.spec);
  f.pixels = largestImagePixels(job);
  // The framebuffers alive at once, and a preview (4 bytes a pixel) in each writer.
  f.bytesPerPixel = framebufferBytesPerPixel(job.aovs) * uint64_t(framebuffersAlive(writers)) +
                    (job.previewPattern.empty() ? 0 : 4 * uint64_t(std::max(writers, 1)));
  return f;
}

/// The memory of scenes a and b alive together (meshes, BVHs), with the larger framebuffers.
MemoryEstimate pairEstimate(const SceneFootprint& a, const SceneFootprint& b) {
  std::vector<std::string> specs = a.specs;
  specs.insert(specs.end(), b.specs.begin(), b.specs.end());
  return estimateMemory(specs, std::max(a.pixels, b.pixels), 1, 0,
                        std::max(a.bytesPerPixel, b.bytesPerPixel));
}

/// --max-memory: refuses the job before anything is loaded when its estimate is too large. With
/// "scenes", two consecutive scenes are alive at once (one rendering, the next loading): the
/// estimate is that of the largest consecutive pair. The image codec, once a scene loads it,
/// stays: it counts in every estimate when any scene writes through it.
void checkJobMemory(const JobFile& jobs, const std::string& maxMemory, bool overlap) {
  const uint64_t limit = parseMemoryLimit("--max-memory", maxMemory);
  if (!limit) return;
  // The batch runs on the first scene's threads (runBatch).
  const int threads = resolvedThreads(jobs.scenes.front().threads);
  std::vector<SceneFootprint> footprints;
  for (const Job& job : jobs.scenes)
    footprints.push_back(footprintOf(job, writersOf(job, threads, overlap)));
  const uint64_t codecBytes = anyWritesThroughImageCodec(jobs) ? kImageCodecBytes : 0;
  // The tables' cache serves every scene: the job's cameras together.
  std::vector<CameraParams> cameras;
  for (const Job& job : jobs.scenes)
    for (const JobImage& image : job.images) cameras.push_back(image.params);
  const uint64_t tableBytes = directionTableBytes(cameras);
  if (footprints.size() == 1) {
    const SceneFootprint& f = footprints.front();
    MemoryEstimate e = estimateMemory(f.specs, f.pixels, 1, 0, f.bytesPerPixel);
    e.imageCodecBytes = codecBytes;
    e.lensTableBytes = tableBytes;
    checkMemoryLimit(e, limit, "--max-memory", maxMemory);
    return;
  }
  size_t worst = 0;
  MemoryEstimate largest;
  for (size_t k = 0; k + 1 < footprints.size(); ++k) {
    const MemoryEstimate e = pairEstimate(footprints[k], footprints[k + 1]);
    if (e.total() > largest.total()) {
      largest = e;
      worst = k;
    }
  }
  largest.imageCodecBytes = codecBytes;  // the same for every pair
  largest.lensTableBytes = tableBytes;
  try {
    checkMemoryLimit(largest, limit, "--max-memory", maxMemory);
  } catch (const Error& e) {
    throw Error(cat(jobs.path, ": scenes '", jobs.scenes[worst].sceneName, "' and '",
                    jobs.scenes[worst + 1].sceneName,
                    "', alive together (one renders while the next loads): ", e.what()));
  }
}

/// Every file of the plan's images (EXR, dataset files, previews) (what the temporary sweep looks
/// after).
std::vector<std::string> plannedFiles(const BatchPlan& plan) {
  std::vector<std::string> files;
  for (const ImageResult& r : plan.results)
    files.insert(files.end(), r.image->files.begin(), r.image->files.end());
  return files;
}

/// --resume, part 1: removes the temporaries of this shard's files whose process is gone
/// (listing them only, with --dry-run); keeps those of live processes.
void sweepTemporaries(BatchPlan& plan, const std::string& summaryPath, const BatchArgs& a) {
  std::vector<std::string> files = plannedFiles(plan);
  files.push_back(summaryPath);
  for (const TemporaryFile& t : findTemporaries(files)) {
    std::error_code ec;
    if (!t.alive && !a.dryRun) std::filesystem::remove(t.path, ec);
    const char* what = t.alive    ? "kept (process running)"
                       : a.dryRun ? "would remove (process gone)"
                       : ec       ? "could not remove"
                                  : "removed (process gone)";
    if (!t.alive && !a.dryRun && !ec) plan.removedTemporaries.push_back(t.path);
    if (!a.quiet)
      std::fprintf(stderr, "aperture: resume: temporary %s of PID %ld: %s%s\n", t.path.c_str(),
                   t.pid, what, ec ? (": " + ec.message()).c_str() : "");
  }
}

/// --resume, part 2: skips the images whose output matches the job; says why the others that
/// have an output are rendered again.
void checkOutputs(BatchPlan& plan, bool quiet) {
  size_t reused = 0, stale = 0, missing = 0;
  for (ImageResult& r : plan.results) {
    const OutputCheck check = checkOutput(plan.jobs.scenes[r.image->scene], *r.image);
    if (check.state == OutputCheck::State::Reusable) {
      r.status = ImageStatus::Skipped;
      ++reused;
      continue;
    }
    r.staleReason = check.reason;
    ++(check.state == OutputCheck::State::Stale ? stale : missing);
    if (!quiet && check.state == OutputCheck::State::Stale)
      std::fprintf(stderr, "aperture: resume: %s (%s): stale: %s; rendering it again\n",
                   imageLabel(*r.image).c_str(), r.image->output.c_str(), check.reason.c_str());
  }
  if (!quiet)
    std::fprintf(stderr, "aperture: resume: %zu of %zu images up to date, %zu stale, %zu missing\n",
                 reused, plan.results.size(), stale, missing);
}

std::string summaryPathOf(const BatchArgs& a, const BatchPlan& plan) {
  return a.summary.empty() ? defaultSummaryPath(plan.jobs, plan.shard) : a.summary;
}

/// The one-line form's job as a job file of one scene.
JobFile cameraFileJobFile(const CameraFileBatch& b) {
  JobFile file;
  file.scenes.push_back(cameraFileJob(b));
  file.path = file.scenes.front().path;
  file.outputDirectory = file.scenes.front().outputDirectory;
  return file;
}

/// Everything is validated (shard, job file, cameras, mesh files, memory) before anything is
/// loaded; with --resume, stale temporaries are swept and outputs checked.
BatchPlan planBatch(const BatchArgs& a) {
  BatchPlan plan;
  plan.shard = parseShard(a.shard);
  if (a.files.empty()) checkDeepHasLayers(a.cameraFile.deep, a.cameraFile.layers);
  plan.jobs = a.files.empty() ? cameraFileJobFile(a.cameraFile) : readJobFile(a.files.front());
  checkJobMemory(plan.jobs, a.maxMemory, !a.noOverlap);
  // A missing image codec plugin fails here, before anything is loaded or rendered.
  if (anyWritesThroughImageCodec(plan.jobs)) imageCodec();
  if (!a.quiet && !plan.shard.origin.empty())
    std::fprintf(stderr, "aperture: shard %zu of %zu from %s\n", plan.shard.k, plan.shard.n,
                 plan.shard.origin.c_str());
  if (!a.quiet && a.shard.empty() && !unshardedSchedulerNote().empty())
    std::fprintf(stderr, "aperture: note: %s\n", unshardedSchedulerNote().c_str());
  for (const Job& job : plan.jobs.scenes)
    for (const JobImage& image : job.images)
      if (plan.shard.contains(image.index)) {
        plan.results.emplace_back();
        plan.results.back().image = &image;
      }
  if (a.resume) {
    sweepTemporaries(plan, summaryPathOf(a, plan), a);
    checkOutputs(plan, a.quiet);
  }
  for (const ImageResult& r : plan.results) plan.toRender += r.status != ImageStatus::Skipped;
  return plan;
}

/// Each scene's results in the plan (results are in scene order), scenes without any included.
std::vector<SceneImages> sceneImagesOf(const BatchPlan& plan) {
  std::vector<SceneImages> scenes(plan.jobs.scenes.size());
  for (size_t s = 0; s < scenes.size(); ++s) scenes[s].scene = s;
  size_t at = 0;
  for (SceneImages& s : scenes) {
    s.first = at;
    while (at < plan.results.size() && plan.results[at].image->scene == s.scene) {
      s.toRender += plan.results[at].status != ImageStatus::Skipped;
      ++at;
    }
    s.last = at;
  }
  return scenes;
}

int printDryRun(const BatchPlan& plan) {
  std::printf("%s: %zu images in the job, %zu in this shard, %zu to render\n",
              plan.jobs.path.c_str(), plan.jobs.imageCount(), plan.results.size(), plan.toRender);
  for (const ImageResult& r : plan.results) {
    const std::string camera =
        plan.jobs.multiScene ? plan.jobs.scenes[r.image->scene].sceneName + "/" + r.image->camera
                             : r.image->camera;
    std::printf("%6zu  %-20s %7d  %-9s %s%s%s\n", r.image->index, camera.c_str(), r.image->frame,
                r.status == ImageStatus::Skipped ? "skip" : "render", r.image->output.c_str(),
                r.staleReason.empty() ? "" : "  stale: ", r.staleReason.c_str());
  }
  return 0;
}

/// Renders the scene's images not skipped, handing each to the writer threads (drained before
/// returning, so the scene can be released), as many as writersOf gives for the batch's
/// `threads`; returns the render seconds.
double renderBatchImages(BatchPlan& plan, const SceneImages& images, const LoadedScene& scene,
                         const BatchArgs& a, int threads, Progress& progress) {
  const Job& job = plan.jobs.scenes[images.scene];
  const PreviewOptions preview = batchPreviewOptions(job, scene.worldLo, scene.worldHi);
  double renderSeconds = 0;
  auto write = [&](ImageWriter::Task& task) {
    const auto t0 = BatchClock::now();
    if (job.idCounts) task.result->idCounts = idCountsOf(task.view.fb);
    writeImageFiles(
        *task.result, task.view,
        viewMetadata(task.view, scene.names, job.aovs, job.build, job.placement, scene.ids),
        job.exr, preview, job.cameraFiles, job.writesExr, job.dataset);
    task.result->writeSeconds = secondsSince(t0);
    task.view = RenderedView();
    progress.finished(*task.result);
  };
  ImageWriter writer(write, writersOf(job, threads, !a.noOverlap), kImagesWaiting);
  for (size_t i = images.first; i < images.last; ++i) {
    ImageResult& r = plan.results[i];
    if (r.status == ImageStatus::Skipped) continue;
    if (gInterrupted) {
      r.status = ImageStatus::Interrupted;
      continue;
    }
    try {
      ensureParentDirectory(r.image->output, "output");
      RenderedView view = renderView(*scene.scene, r.image->params, job.render, job.aovs);
      r.renderSeconds = view.stats.seconds;
      r.rays = view.stats.raysTraced;
      renderSeconds += view.stats.seconds;
      progress.rendered(r);
      writer.push({&r, std::move(view)});
    } catch (const std::exception& e) {
      r.status = ImageStatus::Failed;
      r.error = e.what();
      progress.finished(r);
    }
  }
  writer.finish();
  return renderSeconds;
}

std::vector<CameraParams> camerasToRender(const BatchPlan& plan, const SceneImages& images) {
  std::vector<CameraParams> cameras;
  for (size_t i = images.first; i < images.last; ++i)
    if (plan.results[i].status != ImageStatus::Skipped)
      cameras.push_back(plan.results[i].image->params);
  return cameras;
}

BatchRun describeRun(const BatchPlan& plan, const BatchArgs& a) {
  BatchRun run;
  run.jobFile = &plan.jobs;
  run.shard = &plan.shard;
  for (const Job& job : plan.jobs.scenes) run.scenes.push_back(unloadedSceneReport(job));
  for (const ImageResult& r : plan.results) ++run.scenes[r.image->scene].images;
  run.resume = a.resume;
  run.overlap = !a.noOverlap;
  run.quiet = a.quiet;
  run.removedTemporaries = plan.removedTemporaries;
  return run;
}

/// A scene as the pipeline hands it over: loaded and built, or why it could not be.
struct PipelinedScene {
  std::unique_ptr<LoadedScene> loaded;
  std::string error;
};

/// One scene through the one scene set-up; culled for the images this run renders of it.
/// In a job with "scenes", a scene that fails to load fails its images only; a one-scene job
/// stops with the error, as before anything is rendered.
PipelinedScene loadBatchScene(const Device& device, const BatchPlan& plan,
                              const SceneImages& images, bool quiet) {
  const SceneSpec spec = plan.jobs.scenes[images.scene].sceneSpec();
  try {
    auto s = std::make_unique<LoadedScene>(loadSceneMeshes(spec, quiet));
    buildLoadedScene(device, *s, spec, quiet, camerasToRender(plan, images));
    return {std::move(s), ""};
  } catch (const std::exception& e) {
    if (!plan.jobs.multiScene) throw;
    return {nullptr, e.what()};
  }
}

/// A scene that could not be loaded: its images fail with the reason.
void failSceneImages(BatchPlan& plan, const SceneImages& images, const std::string& error,
                     Progress& progress) {
  const std::string& name = plan.jobs.scenes[images.scene].sceneName;
  for (size_t i = images.first; i < images.last; ++i) {
    ImageResult& r = plan.results[i];
    if (r.status == ImageStatus::Skipped) continue;
    r.status = ImageStatus::Failed;
    r.error = cat("scene '", name, "' could not be loaded: ", error);
    progress.finished(r);
  }
}

/// After Ctrl-C: the scene's images not yet done are interrupted.
void markInterrupted(BatchPlan& plan, const SceneImages& images) {
  for (size_t i = images.first; i < images.last; ++i)
    if (plan.results[i].status == ImageStatus::Pending)
      plan.results[i].status = ImageStatus::Interrupted;
}

/// "camera_files": the COLMAP text model of every image of one scene whose EXR exists
/// (rendered now or reused), in the scene's output directory's sparse/ (sparse.shard-K-of-N/
/// for a shard); sparse.<scene>/ when scenes share their output directory.
void writeRenderedCameras(const BatchPlan& plan, const SceneImages& images, bool quiet) {
  const Job& job = plan.jobs.scenes[images.scene];
  CameraFile file;
  for (size_t i = images.first; i < images.last; ++i) {
    const ImageResult& r = plan.results[i];
    if (r.status != ImageStatus::Ok && r.status != ImageStatus::Skipped) continue;
    const std::optional<CalibratedView> view = calibratedViewOf(r.image->params);
    if (!view) continue;
    auto same = std::find(file.sensors.begin(), file.sensors.end(), view->sensor);
    if (same == file.sensors.end()) {
      file.sensors.push_back(view->sensor);
      file.sensorIds.push_back(std::to_string(file.sensors.size()));
      same = file.sensors.end() - 1;
    }
    const std::string name = std::filesystem::path(r.image->output)
                                 .lexically_relative(job.outputDirectory)
                                 .generic_string();
    file.images.push_back({name, int(same - file.sensors.begin()), view->cvCameraFromWorld});
  }
  if (file.images.empty()) return;
  bool sharedDirectory = false;
  for (const Job& other : plan.jobs.scenes)
    sharedDirectory |= &other != &job && other.outputDirectory == job.outputDirectory;
  std::string name = sharedDirectory ? "sparse." + job.sceneName : std::string("sparse");
  if (plan.shard.n > 1) name += cat(".shard-", plan.shard.k, "-of-", plan.shard.n);
  file.path = (std::filesystem::path(job.outputDirectory) / name).string();
  writeColmapText(file, file.path);
  if (!quiet)
    std::fprintf(stderr, "aperture: wrote the COLMAP model of %zu images to %s\n",
                 file.images.size(), file.path.c_str());
}

/// Renders every scene that has images to render: scene k renders while the next such scene
/// loads and builds (apps/batch/scene_pipeline.h). The clock starts when the first scene is built
/// (nothing can overlap its load), as it does for a one-scene job.
void renderScenes(BatchPlan& plan, const BatchArgs& a, const Device& device, BatchRun& run,
                  Progress& progress) {
  std::vector<SceneImages> pending;
  for (const SceneImages& s : sceneImagesOf(plan))
    if (s.toRender) pending.push_back(s);
  std::optional<BatchClock::time_point> start;
  // After Ctrl-C the scenes still to come are not loaded: their images are interrupted.
  const std::function<PipelinedScene(size_t)> load = [&](size_t k) {
    return gInterrupted ? PipelinedScene() : loadBatchScene(device, plan, pending[k], a.quiet);
  };
  const std::function<void(size_t, PipelinedScene&)> render = [&](size_t k, PipelinedScene& s) {
    if (!start) start = BatchClock::now();
    const SceneImages& images = pending[k];
    if (plan.jobs.multiScene)
      progress.startScene(images.scene + 1, plan.jobs.scenes.size(),
                          plan.jobs.scenes[images.scene].sceneName, images.toRender);
    SceneReport& report = run.scenes[images.scene];
    if (gInterrupted) return markInterrupted(plan, images);
    if (!s.loaded) {
      report.error = s.error;
      failSceneImages(plan, images, s.error, progress);
      return;
    }
    recordLoadedScene(report, *s.loaded);
    run.renderSeconds += renderBatchImages(plan, images, *s.loaded, a, run.threads, progress);
    // The job's LiDAR sensors scan the same scene once its images are rendered.
    for (const JobLidar& lidar : plan.jobs.scenes[images.scene].lidars)
      writeScans(*s.loaded->scene, lidar.request, lidar.prepared, device.isaName(), run.threads);
  };
  pipelineScenes(pending.size(), load, render);
  run.elapsedSeconds = start ? secondsSince(*start) : 0;
}

int runBatch(const BatchArgs& a) {
  BatchPlan plan = planBatch(a);
  if (a.dryRun) return printDryRun(plan);

  ThreadLimit threads(plan.jobs.scenes.front().threads);
  const ExrEncodingThreads encoding(threads.threads(), plan.jobs.scenes.front().exr.compression);
  Device device;
  BatchRun run = describeRun(plan, a);
  run.threads = threads.threads();
  run.isa = device.isaName();
  Progress progress(plan.toRender, a.quiet);
  SigintGuard sigint;
  gInterrupted = 0;
  // With everything up to date, no mesh is loaded and no BVH built.
  renderScenes(plan, a, device, run, progress);
  progress.end();
  run.interrupted = gInterrupted != 0;
  for (const SceneImages& s : sceneImagesOf(plan))
    if (plan.jobs.scenes[s.scene].cameraFiles) writeRenderedCameras(plan, s, a.quiet);
  return reportBatch(run, plan.results, batchSummary(run, plan.results), summaryPathOf(a, plan));
}

/// Checks the positional files against the mode; false after a usage message.
bool checkFiles(const BatchArgs& a) {
  if (!a.mergeOut.empty() || a.files.size() == 1) return true;
  if (a.files.empty() && !a.cameraFile.cameras.empty()) return true;
  if (a.files.empty()) {
    std::fprintf(stderr,
                 "aperture batch: give a job file, or --mesh MESH --cameras PATH --out DIR "
                 "(see aperture batch --help)\n");
    return false;
  }
  std::fprintf(stderr,
               "aperture batch: give one job file (got %zu files; several only with "
               "--merge-summaries OUT.json IN...)\n",
               a.files.size());
  return false;
}

const char* const kShardHelp =
    "Render only the images whose index in the job is K modulo N. K/N (0 <= K < N); 'slurm': a "
    "Slurm job array, K = (SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN) / SLURM_ARRAY_TASK_STEP, "
    "N = SLURM_ARRAY_TASK_COUNT; 'k8s/N': a Kubernetes indexed Job of N completions, K = "
    "JOB_COMPLETION_INDEX. Without --shard the environment is not read: every image renders";

}  // namespace

Command addBatchCommand(CLI::App& app) {
  auto args = std::make_shared<BatchArgs>();
  CLI::App* sub =
      app.add_subcommand("batch", "Render every image of a job file (docs/batch.md) over one BVH");
  sub->add_option("job", args->files,
                  "Job file (JSON); with --merge-summaries, the summaries to merge");
  CameraFileBatch& cf = args->cameraFile;
  const char* const group = "Without a job file: the images of a camera file";
  sub->add_option("--cameras", cf.cameras, kCameraFileHelp)->group(group)->type_name("PATH");
  sub->add_option("--mesh", cf.meshes,
                  "Mesh or scene file (PLY, OBJ, glTF .gltf/.glb) or procedural:NAME; repeatable")
      ->group(group);
  sub->add_option("--gltf-scene", cf.gltfScene,
                  "The scene (index into \"scenes\") of every glTF --mesh (the job's "
                  "scene.gltf_scene). Default: the file's \"scene\", else 0")
      ->group(group)
      ->type_name("N");
  sub->add_option("--out", cf.outDir, "Output folder: DIR/<image name>.exr, subfolders kept")
      ->group(group)
      ->type_name("DIR");
  sub->add_option("--image", cf.images, "Render only this image (repeatable)")
      ->group(group)
      ->type_name("NAME");
  sub->add_option("--aov", cf.aovs,
                  "AOVs: color, depth, distance, normal, position, primid, geomid, all, "
                  "shading-normal, face.NAME, vertex.NAME")
      ->group(group)
      ->capture_default_str();
  sub->add_option("--spp", cf.spp, "Samples per pixel")->group(group);
  sub->add_option("--size", cf.size,
                  "Image size W,H of cameras that carry none (glTF cameras; without it the "
                  "height is 540 and the width follows the camera's aspect ratio)")
      ->group(group)
      ->delimiter(',')
      ->expected(2)
      ->type_name("W,H");
  sub->add_option("--format", cf.format,
                  "exr: every AOV in DIR/<image name>.exr; png (16-bit depth), pfm, npy, tif: "
                  "the one AOV of --aov in DIR/<image name>.<format>")
      ->group(group)
      ->capture_default_str();
  sub->add_option("--depth-scale", cf.depthScale,
                  "16-bit PNG: value = round(depth * S), 0 for misses and out of range "
                  "(default 1000: millimetres per metre)")
      ->group(group)
      ->type_name("S");
  addLayersOption(*sub, cf.layers, group);
  addDeepOption(*sub, cf.deep, group);
  sub->add_flag("--preview", cf.preview, "Also write DIR/<image name>.png")->group(group);
  sub->add_option("--normal-frame", cf.normalFrame,
                  "Frame of normal and shading-normal: world, opencv or opengl")
      ->group(group);
  sub->add_flag("--id-counts", cf.idCounts,
                "summary.json: pixels per id of geomid and the face./vertex. AOVs, per image")
      ->group(group);
  sub->add_flag("--resume", args->resume,
                "Skip images whose EXR is complete and matches the job and whose other files "
                "(preview, dataset files) exist; remove "
                "temporaries of this shard's files left by processes that no longer exist");
  sub->add_option("--shard", args->shard, kShardHelp);
  sub->add_option("--summary", args->summary,
                  "summary.json path (default: the output directory, summary.json or "
                  "summary.shard-K-of-N.json)");
  sub->add_option("--merge-summaries", args->mergeOut,
                  "Merge the shards' summaries given as arguments into OUT.json, list the images "
                  "none of them has ok; exit 1 when some are missing")
      ->type_name("OUT.json");
  sub->add_flag("--quiet", args->quiet, "No progress, log lines or summary table");
  sub->add_option("--max-memory", args->maxMemory,
                  "Refuse the job before loading when its estimated memory (meshes, BVH, the "
                  "framebuffers: one rendering, one waiting, one in each writer thread) exceeds "
                  "BYTES (suffix K, M, G, T) or, with 'auto', MemAvailable");
  sub->add_flag("--dry-run", args->dryRun,
                "Validate the job and list the images (with --resume: what is stale); render "
                "nothing");
  sub->add_flag("--no-overlap", args->noOverlap,
                "Write each image before rendering the next (to measure what overlap gains)");
  return [args] {
    if (!checkFiles(*args)) return 2;
    if (!args->files.empty() && !args->cameraFile.cameras.empty()) {
      std::fprintf(stderr, "aperture batch: give a job file or --cameras, not both\n");
      return 2;
    }
    if (!args->mergeOut.empty()) return mergeSummaries(args->mergeOut, args->files, args->quiet);
    return runBatch(*args);
  };
}

}  // namespace aperture::app
