// `aperture batch`: many views of one scene from a job file; the BVH is built once, frames
// render with all cores while a writer thread encodes the previous frame.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "apps/commands.h"
#include "apps/job.h"
#include "apps/options.h"
#include "apps/outputs.h"
#include "apps/view.h"
#include "cameras/culling.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/exr.h"
#include "core/image.h"
#include "core/limits.h"

namespace aperture::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

struct BatchArgs {
  std::string job, shard, summary;
  bool resume = false, quiet = false, dryRun = false, noOverlap = false;
  std::string maxMemory;
};

struct Shard {
  size_t k = 0, n = 1;
};

Shard parseShard(const std::string& text) {
  Shard s;
  if (text.empty()) return s;
  const size_t slash = text.find('/');
  auto number = [&](const std::string& part, size_t& out) {
    if (part.empty() || part.size() > 9 ||
        part.find_first_not_of("0123456789") != std::string::npos)
      return false;
    out = std::stoul(part);
    return true;
  };
  if (slash == std::string::npos || !number(text.substr(0, slash), s.k) ||
      !number(text.substr(slash + 1), s.n) || s.n < 1 || s.k >= s.n)
    throw Error(cat("--shard: '", text, "' must be K/N with 0 <= K < N (e.g. 0/4)"));
  return s;
}

// SIGINT sets this; the frame loop checks it between frames. SA_RESETHAND makes a second
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

enum class Status { Pending, Ok, Failed, Skipped, Interrupted };
const char* statusName(Status s) {
  switch (s) {
    case Status::Pending:
      return "pending";
    case Status::Ok:
      return "ok";
    case Status::Failed:
      return "failed";
    case Status::Skipped:
      return "skipped";
    case Status::Interrupted:
      return "interrupted";
  }
  return "?";
}

struct FrameResult {
  const JobImage* frame = nullptr;
  Status status = Status::Pending;
  std::string error;
  double renderSeconds = 0, writeSeconds = 0;
  uint64_t rays = 0;
  double mrays() const { return renderSeconds > 0 ? double(rays) / renderSeconds * 1e-6 : 0; }
};

std::string frameLabel(const JobImage& f) { return cat(f.camera, " frame ", f.frame); }

std::string hms(double seconds) {
  const long s = long(seconds + 0.5);
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  return buf;
}

/// Frames done / total, Mrays/s, elapsed and ETA: one updating line on a terminal, a log line
/// per frame otherwise, nothing with --quiet. Called from the render and writer threads.
class Progress {
 public:
  Progress(size_t total, bool quiet)
      : total_(total), quiet_(quiet), tty_(::isatty(STDERR_FILENO) == 1), start_(Clock::now()) {}

  void rendered(const FrameResult& r) {
    std::lock_guard<std::mutex> lock(mutex_);
    rays_ += r.rays;
  }
  void finished(const FrameResult& r) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    if (quiet_) return;
    const double elapsed = secondsSince(start_);
    const double mrays = elapsed > 0 ? double(rays_) / elapsed * 1e-6 : 0;
    const double eta = done_ ? elapsed / double(done_) * double(total_ - done_) : 0;
    if (r.status == Status::Failed) {
      clearLine();
      std::fprintf(stderr, "aperture: %s failed: %s\n", frameLabel(*r.frame).c_str(),
                   r.error.c_str());
    }
    if (tty_) {
      std::fprintf(stderr, "\r\033[K[%zu/%zu frames] %.1f Mrays/s  elapsed %s  ETA %s", done_,
                   total_, mrays, hms(elapsed).c_str(), hms(eta).c_str());
      drawn_ = true;
    } else if (r.status == Status::Ok) {
      std::fprintf(stderr,
                   "aperture: [%zu/%zu] %s -> %s (render %.3f s, %.1f Mrays/s; write %.3f s); "
                   "elapsed %s, ETA %s\n",
                   done_, total_, frameLabel(*r.frame).c_str(), r.frame->output.c_str(),
                   r.renderSeconds, r.mrays(), r.writeSeconds, hms(elapsed).c_str(),
                   hms(eta).c_str());
    }
    std::fflush(stderr);
  }
  void end() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  void clearLine() {
    if (drawn_) std::fprintf(stderr, "\r\033[K");
  }
  std::mutex mutex_;
  size_t total_, done_ = 0;
  uint64_t rays_ = 0;
  bool quiet_, tty_, drawn_ = false;
  Clock::time_point start_;
};

/// Encodes and writes rendered frames. Threaded, it holds at most `capacity` frames waiting,
/// so the renderer blocks instead of piling up framebuffers; unthreaded, write() runs inline.
class FrameWriter {
 public:
  struct Task {
    FrameResult* result;
    RenderedView view;
  };
  using WriteFn = std::function<void(Task&)>;

  FrameWriter(WriteFn write, bool threaded, size_t capacity)
      : write_(std::move(write)), capacity_(capacity) {
    if (threaded) thread_ = std::thread([this] { loop(); });
  }
  ~FrameWriter() { finish(); }

  void push(Task task) {
    if (!thread_.joinable()) {
      write_(task);
      return;
    }
    std::unique_lock<std::mutex> lock(mutex_);
    space_.wait(lock, [&] { return queue_.size() < capacity_; });
    queue_.push_back(std::move(task));
    ready_.notify_one();
  }

  /// Writes what is queued and stops the thread.
  void finish() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    ready_.notify_one();
    thread_.join();
  }

 private:
  void loop() {
    for (;;) {
      std::unique_lock<std::mutex> lock(mutex_);
      ready_.wait(lock, [&] { return closed_ || !queue_.empty(); });
      if (queue_.empty()) return;
      Task task = std::move(queue_.front());
      queue_.pop_front();
      space_.notify_one();
      lock.unlock();
      write_(task);
    }
  }

  WriteFn write_;
  size_t capacity_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<Task> queue_;
  bool closed_ = false;
  std::thread thread_;
};

/// The job's meshes, each file loaded once, and the Embree scene over their placements.
struct BatchScene {
  std::deque<Mesh> meshes;
  std::deque<TriangleSubset> subsets;  ///< with performance.cull
  std::vector<std::string> names;      ///< one per job mesh entry
  std::unique_ptr<Scene> scene;
  double loadSeconds = 0;
};

/// `cameras`: the frames this run renders (culling keeps what they may see).
BatchScene buildScene(const Device& device, const Job& job, bool quiet,
                      const std::vector<CameraParams>& cameras) {
  BatchScene s;
  std::map<std::string, size_t> uses;
  for (const JobMesh& m : job.meshes) ++uses[m.spec];
  const auto start = Clock::now();
  // A file used once with a transform has it baked in at load; a file used several times is
  // loaded untransformed and placed by instances.
  std::map<std::string, Mesh*> bySpec;
  for (const JobMesh& m : job.meshes) {
    if (bySpec.count(m.spec)) continue;
    LoadOptions lo;
    lo.placement = job.placement;
    if (uses[m.spec] == 1) lo.transform = m.worldFromMesh;
    s.meshes.push_back(loadMesh(m.spec, lo));
    if (!quiet) logLoadedMesh(s.meshes.back());
    bySpec[m.spec] = &s.meshes.back();
  }
  s.loadSeconds = secondsSince(start);

  std::vector<SceneObject> objects;
  for (const JobMesh& m : job.meshes) {
    const bool instanced = uses[m.spec] > 1;
    objects.push_back(
        {bySpec[m.spec], instanced ? m.worldFromMesh.value_or(glm::dmat4(1.0)) : glm::dmat4(1.0)});
    s.names.push_back(m.spec);
  }
  // Meshes used once share the render origin (the first object's anchor), so they are
  // attached directly rather than instanced.
  const glm::dvec3 origin(objects[0].worldFromMesh * glm::dvec4(objects[0].mesh->anchor, 1.0));
  for (auto& [spec, mesh] : bySpec)
    if (uses[spec] == 1) moveAnchor(*mesh, origin);
  if (job.cull && !cameras.empty()) {
    const CameraCuller culler = cullerFor(cameras, origin);
    if (culler.seesEverything) {
      if (!quiet)
        std::fprintf(stderr, "aperture: cull: a panorama camera sees all space; nothing culled\n");
    } else {
      const CullStats c = cullObjects(objects, culler.test(), s.subsets);
      if (!quiet) logCullStats(c, cameras.size());
    }
  }
  s.scene = std::make_unique<Scene>(device, objects, job.build);
  if (!quiet) {
    const BuildStats& b = s.scene->stats();
    std::fprintf(stderr,
                 "aperture: built BVH (%s%s%s): %zu triangles (%zu stored, %zu instances) in "
                 "%.3f s, Embree memory %.1f MB\n",
                 bvhQualityName(job.build.quality), job.build.robust ? ", robust" : "",
                 job.build.compact ? ", compact" : "", b.triangles, b.uniqueTriangles,
                 s.scene->instanceCount(), b.buildSeconds, b.embreeBytes / 1e6);
  }
  return s;
}

std::string defaultSummaryPath(const Job& job, const Shard& shard) {
  const std::string name =
      shard.n > 1 ? cat("summary.shard-", shard.k, "-of-", shard.n, ".json") : "summary.json";
  return (fs::path(job.outputDirectory) / name).lexically_normal().string();
}

void printTable(const std::vector<FrameResult>& results) {
  std::printf("%-20s %7s  %-11s %9s %8s %9s  %s\n", "camera", "frame", "status", "render s",
              "write s", "Mrays/s", "output");
  for (const FrameResult& r : results)
    std::printf("%-20s %7d  %-11s %9.3f %8.3f %9.1f  %s\n", r.frame->camera.c_str(), r.frame->frame,
                statusName(r.status), r.renderSeconds, r.writeSeconds, r.mrays(),
                r.frame->output.c_str());
}

int runBatch(const BatchArgs& a) {
  // Everything is validated (job file, cameras, mesh files) before anything is loaded.
  const Shard shard = parseShard(a.shard);
  const Job job = parseJob(a.job);
  if (const uint64_t limit = parseMemoryLimit("--max-memory", a.maxMemory)) {
    std::vector<std::string> specs;
    for (const JobMesh& m : job.meshes)
      if (std::find(specs.begin(), specs.end(), m.spec) == specs.end()) specs.push_back(m.spec);
    uint64_t pixels = 0;
    for (const JobImage& f : job.images)
      pixels = std::max(pixels, uint64_t(f.params.width) * uint64_t(f.params.height));
    // Two framebuffers live at once: the frame being rendered and the one being written.
    const uint64_t perPixel =
        framebufferBytesPerPixel(job.aovs) * 2 + (job.previewPattern.empty() ? 0 : 4);
    checkMemoryLimit(estimateMemory(specs, pixels, 1, 0, perPixel), limit, "--max-memory",
                     a.maxMemory);
  }

  std::vector<FrameResult> results;
  for (const JobImage& f : job.images)
    if (f.index % shard.n == shard.k) {
      results.emplace_back();
      results.back().frame = &f;
    }
  size_t toRender = 0;
  for (FrameResult& r : results) {
    if (a.resume && fs::exists(r.frame->output) && isCompleteExr(r.frame->output))
      r.status = Status::Skipped;
    else
      ++toRender;
  }

  if (a.dryRun) {
    std::printf("%s: %zu frames in the job, %zu in this shard, %zu to render\n", job.path.c_str(),
                job.images.size(), results.size(), toRender);
    for (const FrameResult& r : results)
      std::printf("%6zu  %-20s %7d  %-9s %s\n", r.frame->index, r.frame->camera.c_str(),
                  r.frame->frame, r.status == Status::Skipped ? "skip" : "render",
                  r.frame->output.c_str());
    return 0;
  }

  const std::string summaryPath = a.summary.empty() ? defaultSummaryPath(job, shard) : a.summary;
  ThreadLimit threads(job.threads);
  Device device;
  std::vector<CameraParams> cameras;
  for (const FrameResult& r : results)
    if (r.status != Status::Skipped) cameras.push_back(r.frame->params);
  const BatchScene scene = buildScene(device, job, a.quiet, cameras);
  const BuildStats& build = scene.scene->stats();
  const PreviewOptions preview = batchPreviewOptions(job, scene.meshes);

  Progress progress(toRender, a.quiet);
  SigintGuard sigint;
  gInterrupted = 0;
  const auto start = Clock::now();
  double renderSeconds = 0;

  auto write = [&](FrameWriter::Task& task) {
    FrameResult& r = *task.result;
    const auto t0 = Clock::now();
    try {
      const ExrMetadata meta =
          viewMetadata(task.view, scene.names, job.aovs, job.build.quality, job.placement);
      writeViewOutputs(task.view, meta, job.exr, r.frame->output, r.frame->preview, preview);
      r.status = Status::Ok;
    } catch (const std::exception& e) {
      r.status = Status::Failed;
      r.error = e.what();
    }
    r.writeSeconds = secondsSince(t0);
    task.view = RenderedView();
    progress.finished(r);
  };

  {
    FrameWriter writer(write, !a.noOverlap, 1);
    for (FrameResult& r : results) {
      if (r.status == Status::Skipped) continue;
      if (gInterrupted) {
        r.status = Status::Interrupted;
        continue;
      }
      try {
        ensureParentDirectory(r.frame->output, "output");
        RenderedView view = renderView(*scene.scene, r.frame->params, job.render, job.aovs);
        r.renderSeconds = view.stats.seconds;
        r.rays = view.stats.raysTraced;
        renderSeconds += view.stats.seconds;
        progress.rendered(r);
        writer.push({&r, std::move(view)});
      } catch (const std::exception& e) {
        r.status = Status::Failed;
        r.error = e.what();
        progress.finished(r);
      }
    }
    writer.finish();
  }
  progress.end();
  const double elapsed = secondsSince(start);

  std::vector<std::string> failed, skipped, interrupted;
  uint64_t rays = 0;
  double writeSeconds = 0;
  nlohmann::json frames = nlohmann::json::array();
  for (const FrameResult& r : results) {
    rays += r.rays;
    writeSeconds += r.writeSeconds;
    if (r.status == Status::Failed) failed.push_back(frameLabel(*r.frame));
    if (r.status == Status::Skipped) skipped.push_back(r.frame->output);
    if (r.status == Status::Interrupted) interrupted.push_back(frameLabel(*r.frame));
    const glm::dvec3& eye = r.frame->params.eye;
    nlohmann::json f = {{"index", r.frame->index},         {"camera", r.frame->camera},
                        {"frame", r.frame->frame},         {"output", r.frame->output},
                        {"status", statusName(r.status)},  {"render_seconds", r.renderSeconds},
                        {"write_seconds", r.writeSeconds}, {"rays", r.rays},
                        {"mrays_per_s", r.mrays()},        {"eye", {eye.x, eye.y, eye.z}}};
    if (!r.frame->preview.empty()) f["preview"] = r.frame->preview;
    if (!r.error.empty()) f["error"] = r.error;
    frames.push_back(f);
  }
  const size_t ok = size_t(std::count_if(
      results.begin(), results.end(), [](const FrameResult& r) { return r.status == Status::Ok; }));
  nlohmann::json summary = {{"job", job.path},
                            {"aperture_version", APERTURE_VERSION},
                            {"shard", {{"k", shard.k}, {"n", shard.n}}},
                            {"resume", a.resume},
                            {"overlap_writes", !a.noOverlap},
                            {"frames_in_job", job.images.size()},
                            {"frames_in_shard", results.size()},
                            {"frames_ok", ok},
                            {"frames_failed", failed.size()},
                            {"frames_skipped", skipped.size()},
                            {"frames_interrupted", interrupted.size()},
                            {"failed", failed},
                            {"skipped", skipped},
                            {"interrupted", interrupted},
                            {"meshes", scene.names},
                            {"load_seconds", scene.loadSeconds},
                            {"bvh_builds", 1},
                            {"build_seconds", build.buildSeconds},
                            {"triangles", build.triangles},
                            {"unique_triangles", build.uniqueTriangles},
                            {"instances", scene.scene->instanceCount()},
                            {"embree_bytes", build.embreeBytes},
                            {"threads", threads.threads()},
                            {"isa", device.isaName()},
                            {"width", job.width},
                            {"height", job.height},
                            {"spp", job.render.spp},
                            {"aovs", aovListString(job.aovs)},
                            {"elapsed_seconds", elapsed},
                            {"render_seconds", renderSeconds},
                            {"write_seconds", writeSeconds},
                            {"rays", rays},
                            {"mrays_per_s", elapsed > 0 ? double(rays) / elapsed * 1e-6 : 0.0},
                            {"frames", frames}};

  if (!a.quiet) {
    printTable(results);
    std::printf(
        "%zu ok, %zu failed, %zu skipped, %zu interrupted; %.3f s elapsed (render %.3f s, "
        "write %.3f s%s), %.1f Mrays/s; BVH built once in %.3f s\n",
        ok, failed.size(), skipped.size(), interrupted.size(), elapsed, renderSeconds, writeSeconds,
        a.noOverlap ? "" : ", overlapped", double(rays) / elapsed * 1e-6, build.buildSeconds);
  }
  try {
    ensureParentDirectory(summaryPath, "--summary");
    writeTextAtomically(summaryPath, summary.dump(2) + "\n");
    if (!a.quiet) std::fprintf(stderr, "aperture: wrote %s\n", summaryPath.c_str());
  } catch (const Error& e) {
    std::fprintf(stderr, "aperture: error: %s\n", e.what());
    if (failed.empty() && !gInterrupted) return 1;
  }

  if (gInterrupted) {
    std::fprintf(stderr, "aperture: interrupted: %zu frames written, %zu not rendered\n", ok,
                 interrupted.size());
    return 130;
  }
  if (!failed.empty()) {
    std::string list;
    for (const std::string& f : failed) list += (list.empty() ? "" : ", ") + f;
    std::fprintf(stderr, "aperture: %zu of %zu frames failed: %s\n", failed.size(), results.size(),
                 list.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

Command addBatchCommand(CLI::App& app) {
  auto args = std::make_shared<BatchArgs>();
  CLI::App* sub =
      app.add_subcommand("batch", "Render every frame of a job file (docs/batch.md) over one BVH");
  sub->add_option("job", args->job, "Job file (JSON)")->required();
  sub->add_flag("--resume", args->resume, "Skip frames whose output is already a complete EXR");
  sub->add_option("--shard", args->shard,
                  "Render only frames whose index in the job is K modulo N (K/N, 0 <= K < N)");
  sub->add_option("--summary", args->summary,
                  "summary.json path (default: the output directory, summary.json or "
                  "summary.shard-K-of-N.json)");
  sub->add_flag("--quiet", args->quiet, "No progress, log lines or summary table");
  sub->add_option("--max-memory", args->maxMemory,
                  "Refuse the job before loading when its estimated memory (meshes, BVH, two "
                  "framebuffers) exceeds BYTES (suffix K, M, G, T) or, with 'auto', MemAvailable");
  sub->add_flag("--dry-run", args->dryRun, "Validate the job and list the frames; render nothing");
  sub->add_flag("--no-overlap", args->noOverlap,
                "Write each frame before rendering the next (to measure what overlap gains)");
  return [args] { return runBatch(*args); };
}

}  // namespace aperture::app
