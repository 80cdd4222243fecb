// `aperture batch --resume` (apps/batch/resume.h): outputs are kept only when they match the
// job (every camera model's description round-trips through the EXR header), each kind of
// stale output is rendered again and only that, a failed preview fails its image, and
// temporaries of dead processes are removed while those of live ones are kept.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "apps/batch/resume.h"
#include "apps/jobs/job.h"
#include "cameras/lenses/direction_table.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/exr/exr.h"
#include "core/io/atomic_file.h"
#include "tests/job_support.h"
#include "tests/support.h"

using namespace aperture;
using aperture::app::Job;
using aperture::test::apertureBinary;
using aperture::test::flagValue;
using aperture::test::imagesWithStatus;
using aperture::test::quote;
using aperture::test::readJson;
using aperture::test::runBatch;
using aperture::test::runCommand;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using aperture::test::writeJob;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

/// Five cameras of different models (so every model's describe() must round-trip through the
/// EXR header for its images to be kept), one with a three-frame orbit; with previews.
json resumeJob() {
  return json::parse(R"({
    "scene": {"meshes": [{"path": "procedural:sphere"}]},
    "cameras": [
      {"name": "persp", "eye": [0, 0, 5], "at": [0, 0, 0], "fov": 40},
      {"name": "ortho", "type": "orthographic", "eye": [0, 1, 5], "at": [0, 0, 0],
       "viewport": [3, 2]},
      {"name": "lens", "type": "thinlens", "eye": [1, 0, 5], "at": [0, 0, 0], "fov": 40,
       "aperture": 0.05, "focus": 5},
      {"name": "pano", "type": "equirect", "eye": [0, 0, 3], "at": [0, 0, 0]},
      {"name": "turn", "orbit": {"radius": 5}, "frames": 3, "fov": 40, "shift": [0.1, 0],
       "architectural": true}
    ],
    "size": [32, 24], "spp": 2, "aovs": "color,depth,primid",
    "output": "out/{camera}_{frame}.exr", "preview": "prev/{camera}_{frame}.png"
  })");
}

/// The stale reason the summary gives for image `index` ("" if none).
std::string staleReasonOf(const json& summary, size_t index) {
  for (const json& e : summary["images"])
    if (e["index"] == index) return e.value("stale", "");
  return "";
}

}  // namespace

TEST(BatchResume, UnchangedOutputsAreAllKeptAndNothingIsLoaded) {
  const std::string dir = scratchDir();
  const std::string jobPath = writeJob(dir, resumeJob());
  std::string out;
  ASSERT_EQ(runBatch("--quiet", jobPath, &out), 0) << out;
  EXPECT_EQ(readJson(dir + "/out/summary.json")["images_ok"], 7);
  ASSERT_EQ(runBatch("--resume", jobPath, &out), 0) << out;
  const json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(imagesWithStatus(summary, "skipped").size(), 7u) << out;
  EXPECT_EQ(summary["images_stale"], 0);
  EXPECT_EQ(summary["bvh_builds"], 0);
  EXPECT_EQ(out.find("aperture: loaded"), std::string::npos) << out;
  EXPECT_NE(out.find("resume: 7 of 7 images up to date, 0 stale, 0 missing"), std::string::npos)
      << out;
}

// A distorted camera's EXR records how many of its pixels have a ray, which only the lens's
// direction table counts. That count follows from the lens and the size, which --resume
// compares as they are, so it checks the file without building the table (COLMAP's default
// of one camera per image would otherwise build one per image). In this process the sensor's
// table is not cached before, and checkOutput keeps the file and leaves it unbuilt; asking
// the camera for its whole description (as the check did before) builds it.
TEST(BatchResume, ADistortedCameraIsCheckedWithoutBuildingItsDirectionTable) {
  const std::string dir = scratchDir();
  const std::string jobPath = writeJob(dir, json::parse(R"({
    "scene": {"meshes": [{"path": "procedural:sphere"}]},
    "cameras": [{"name": "cal", "eye": [0, 0, 5], "at": [0, 0, 0],
                 "intrinsics": [20.5, 21, 16, 12], "lens_model": "OPENCV",
                 "distortion": [-0.2, 0.03, 0.0011, -0.0007]}],
    "size": [32, 24], "aovs": "depth", "output": "out/{camera}.exr"})"));
  std::string out;
  ASSERT_EQ(runBatch("--quiet", jobPath, &out), 0) << out;
  const Job job = app::parseJob(jobPath);
  ASSERT_EQ(job.images.size(), 1u);
  const app::JobImage& image = job.images[0];
  const CalibratedSensor sensor = calibratedSensorOf(image.params);
  ASSERT_FALSE(DirectionTable::cached(sensor));
  const app::OutputCheck check = app::checkOutput(job, image);
  EXPECT_EQ(check.state, app::OutputCheck::State::Reusable) << check.reason;
  EXPECT_FALSE(DirectionTable::cached(sensor));
  const auto& recorded = readExrHeader(image.output).meta.camera.extra;
  EXPECT_TRUE(std::any_of(recorded.begin(), recorded.end(), [](const auto& e) {
    return e.first == kValidPixelsExtra && e.second == "768 of 768";
  }));
  (void)makeCamera(image.params)->describe();
  EXPECT_TRUE(DirectionTable::cached(sensor));
}

TEST(BatchResume, EachKindOfStaleOutputIsRenderedAgainAndOnlyThat) {
  const std::string dir = scratchDir();
  json j = resumeJob();
  const std::string jobPath = writeJob(dir, j);
  std::string out;
  ASSERT_EQ(runBatch("--quiet", jobPath, &out), 0) << out;
  const Job job = app::parseJob(jobPath);
  ASSERT_EQ(job.images.size(), 7u);

  // Index 0: an EXR of another size at its path (the same camera rendered at 40x24).
  const CameraParams& p0 = job.images[0].params;
  ASSERT_EQ(
      runCommand(apertureBinary() + " render --quiet --mesh procedural:sphere --size 40,24" +
                     " --spp 2 --aov color,depth,primid --eye " + flagValue(p0.eye) + " --at " +
                     flagValue(*p0.at) + " --fov 40 --out " + quote(job.images[0].output),
                 &out),
      0)
      << out;
  // Index 1: the EXR truncated (the header survives, the last scanlines do not).
  const auto size1 = fs::file_size(job.images[1].output);
  fs::resize_file(job.images[1].output, size1 - 300);
  // Index 3: the preview deleted.
  fs::remove(job.images[3].preview);
  // Indices 4..6: the orbit's camera changed in the job (a wider field of view).
  j["cameras"][4]["fov"] = 45;
  writeJob(dir, j);
  const auto keptTime = fs::last_write_time(job.images[2].output);

  ASSERT_EQ(runBatch("--resume", jobPath, &out), 0) << out;
  const json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(imagesWithStatus(summary, "ok"), (std::set<size_t>{0, 1, 3, 4, 5, 6})) << out;
  EXPECT_EQ(imagesWithStatus(summary, "skipped"), (std::set<size_t>{2})) << out;
  EXPECT_EQ(fs::last_write_time(job.images[2].output), keptTime);
  EXPECT_EQ(staleReasonOf(summary, 0), "size 40x24, job wants 32x24");
  EXPECT_NE(staleReasonOf(summary, 1).find("EXR"), std::string::npos) << staleReasonOf(summary, 1);
  EXPECT_EQ(staleReasonOf(summary, 3), "preview " + job.images[3].preview + " is missing");
  for (size_t k = 4; k < 7; ++k)
    EXPECT_EQ(staleReasonOf(summary, k).rfind("camera ", 0), 0u) << staleReasonOf(summary, k);
  EXPECT_EQ(staleReasonOf(summary, 2), "");
  EXPECT_NE(out.find("persp frame 0 (" + job.images[0].output +
                     "): stale: size 40x24, job wants 32x24; rendering it again"),
            std::string::npos)
      << out;
  // What was rendered again now matches: a third run keeps everything.
  ASSERT_EQ(runBatch("--resume --quiet", jobPath, &out), 0) << out;
  EXPECT_EQ(imagesWithStatus(readJson(dir + "/out/summary.json"), "skipped").size(), 7u);
  EXPECT_TRUE(isCompleteExr(job.images[1].output));
}

TEST(BatchResume, ChangedSizeOrAovsInTheJobRenderEverythingAgain) {
  const std::string dir = scratchDir();
  json j = resumeJob();
  const std::string jobPath = writeJob(dir, j);
  std::string out;
  ASSERT_EQ(runBatch("--quiet", jobPath, &out), 0) << out;
  j["size"] = {40, 24};
  writeJob(dir, j);
  ASSERT_EQ(runBatch("--resume --quiet", jobPath, &out), 0) << out;
  json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(imagesWithStatus(summary, "ok").size(), 7u);
  EXPECT_EQ(staleReasonOf(summary, 5), "size 32x24, job wants 40x24");
  EXPECT_EQ(readExrHeader(app::parseJob(jobPath).images[5].output).width, 40);

  j["aovs"] = "color,depth";  // primID dropped
  writeJob(dir, j);
  ASSERT_EQ(runBatch("--resume --quiet", jobPath, &out), 0) << out;
  summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(imagesWithStatus(summary, "ok").size(), 7u);
  EXPECT_EQ(staleReasonOf(summary, 0), "channels A,B,G,R,Z,primID, job wants A,B,G,R,Z");
}

TEST(BatchResume, AFailedPreviewFailsTheImageAndResumeRendersItAgain) {
  const std::string dir = scratchDir();
  json j = resumeJob();
  j["preview"] = "prev/{camera}/{frame}.png";
  const std::string jobPath = writeJob(dir, j);
  fs::create_directories(dir + "/prev");
  writeFile(dir + "/prev/ortho", "a regular file where the preview directory should be");
  std::string out;
  EXPECT_EQ(runBatch("", jobPath, &out), 1) << out;
  EXPECT_NE(out.find("1 of 7 images failed: ortho frame 0"), std::string::npos) << out;
  json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(summary["images_failed"], 1);
  EXPECT_EQ(summary["failed"], json({"ortho frame 0"}));
  EXPECT_EQ(imagesWithStatus(summary, "failed"), (std::set<size_t>{1}));
  EXPECT_NE(summary["images"][1]["error"].get<std::string>().find("preview"), std::string::npos);

  // The preview is written first, so its failure left no EXR: --resume renders that image
  // again, exit 0.
  const Job job = app::parseJob(jobPath);
  EXPECT_FALSE(fs::exists(job.images[1].output));
  fs::remove(dir + "/prev/ortho");
  ASSERT_EQ(runBatch("--resume --quiet", jobPath, &out), 0) << out;
  summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(imagesWithStatus(summary, "ok"), (std::set<size_t>{1}));
  EXPECT_EQ(imagesWithStatus(summary, "skipped").size(), 6u);
  EXPECT_TRUE(fs::exists(job.images[1].preview));
}

TEST(BatchResume, TemporariesOfDeadProcessesAreRemovedThoseOfLiveOnesKept) {
  const std::string dir = scratchDir();
  const std::string jobPath = writeJob(dir, resumeJob());
  std::string out;
  ASSERT_EQ(runBatch("--quiet", jobPath, &out), 0) << out;
  // A PID that certainly belonged to a process that has exited: a child reaped here.
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);
  ASSERT_TRUE(::kill(child, 0) == -1 && errno == ESRCH) << "PID " << child << " was reused";
  const std::string dead = std::to_string(child), live = std::to_string(::getpid());
  const std::string deadExr = dir + "/out/.persp_0.exr.tmp-" + dead + "-0";
  const std::string deadPng = dir + "/prev/.pano_0.png.tmp-" + dead + "-7.png";
  const std::string deadSummary = dir + "/out/.summary.json.tmp-" + dead + "-3";
  const std::string liveExr = dir + "/out/.ortho_0.exr.tmp-" + live + "-0";
  const std::string foreign = dir + "/out/.other.exr.tmp-" + dead + "-0";  // not this job's
  for (const std::string& p : {deadExr, deadPng, deadSummary, liveExr, foreign})
    writeFile(p, "partial");

  ASSERT_EQ(runBatch("--resume", jobPath, &out), 0) << out;
  EXPECT_FALSE(fs::exists(deadExr));
  EXPECT_FALSE(fs::exists(deadPng));
  EXPECT_FALSE(fs::exists(deadSummary));
  EXPECT_TRUE(fs::exists(liveExr));
  EXPECT_TRUE(fs::exists(foreign));
  EXPECT_NE(out.find(deadExr + " of PID " + dead + ": removed (process gone)"), std::string::npos)
      << out;
  EXPECT_NE(out.find(liveExr + " of PID " + live + ": kept (process running)"), std::string::npos)
      << out;
  const json summary = readJson(dir + "/out/summary.json");
  std::set<std::string> removed;
  for (const json& p : summary["stale_temporaries_removed"]) removed.insert(p);
  EXPECT_EQ(removed, (std::set<std::string>{deadExr, deadPng, deadSummary}));
  EXPECT_EQ(imagesWithStatus(summary, "skipped").size(), 7u);
  // Without --resume nothing is swept.
  writeFile(deadExr, "partial");
  ASSERT_EQ(runBatch("--quiet", jobPath, &out), 0) << out;
  EXPECT_TRUE(fs::exists(deadExr));
}
