// `aperture batch` end to end (apps/cli/cmd_batch.cpp): images equal to `aperture render` bit for
// bit, shards K/N that union to the whole job, failures of one camera, jobs refused before
// rendering, instancing, --dry-run, SIGINT, the previews' shared depth range and --max-memory
// with the writer threads.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "apps/batch/batch_writer.h"
#include "apps/jobs/job.h"
#include "apps/services/limits.h"
#include "core/exr/exr.h"
#include "core/io/image.h"
#include "core/util/error.h"
#include "tests/job_support.h"
#include "tests/support.h"

using namespace aperture;
using aperture::app::Job;
using aperture::test::apertureBinary;
using aperture::test::baseJob;
using aperture::test::flagValue;
using aperture::test::orbitJob;
using aperture::test::quote;
using aperture::test::readJson;
using aperture::test::runCommand;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using aperture::test::writeJob;
using nlohmann::json;
namespace fs = std::filesystem;

TEST(Batch, ThreeCamerasFourFramesEachEqualRenderBitForBit) {
  const std::string dir = scratchDir();
  const json j = orbitJob();
  const std::string jobPath = writeJob(dir, j);
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " batch " + quote(jobPath), &out), 0) << out;
  const json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(summary["bvh_builds"], 1);
  EXPECT_GT(summary["build_seconds"].get<double>(), 0.0);
  EXPECT_EQ(summary["images_ok"], 12);
  ASSERT_EQ(summary["images"].size(), 12u);

  const Job job = app::parseJob(jobPath);
  ASSERT_EQ(job.images.size(), 12u);
  for (const app::JobImage& f : job.images) {
    SCOPED_TRACE(f.output);
    ASSERT_TRUE(isCompleteExr(f.output));
    const CameraParams& p = f.params;
    const std::string single = dir + "/single.exr";
    const std::string cmd = apertureBinary() +
                            " render --quiet --mesh 'procedural:default?tris=20000' --size 64,48" +
                            " --aov all --threads 2 --eye " + flagValue(p.eye) + " --at " +
                            flagValue(*p.at) + " --up " + flagValue(p.up) + " --fov " +
                            std::to_string(int(*p.fovDeg)) + " --out " + quote(single);
    ASSERT_EQ(runCommand(cmd, &out), 0) << cmd << "\n" << out;
    const Framebuffer batch = readExr(f.output), render = readExr(single);
    EXPECT_GT(batch.pixelCount(), 0u);
    EXPECT_EQ(test::differingAovs(batch, render), "");
  }
}

TEST(Batch, ShardsOfThreeUnionToTheFullJobWithNoFrameTwice) {
  const std::string full = scratchDir() + "/full", sharded = scratchDir() + "/sharded";
  fs::create_directories(full);
  fs::create_directories(sharded);
  json j = orbitJob();
  j["aovs"] = "color,depth,primid";
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet " + quote(writeJob(full, j)), &out), 0)
      << out;
  const std::string shardJob = writeJob(sharded, j);
  std::set<size_t> seen;
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet --shard " + std::to_string(k) + "/3 " +
                             quote(shardJob),
                         &out),
              0)
        << out;
    const json summary =
        readJson(sharded + "/out/summary.shard-" + std::to_string(k) + "-of-3.json");
    EXPECT_EQ(summary["bvh_builds"], 1);
    for (const json& f : summary["images"]) {
      const size_t index = f["index"];
      EXPECT_EQ(index % 3, size_t(k));
      EXPECT_EQ(f["status"], "ok");
      EXPECT_TRUE(seen.insert(index).second) << "frame " << index << " rendered twice";
    }
  }
  EXPECT_EQ(seen.size(), 12u);

  std::set<std::string> fullNames, shardNames;
  for (const auto& e : fs::directory_iterator(full + "/out"))
    if (e.path().extension() == ".exr") fullNames.insert(e.path().filename());
  for (const auto& e : fs::directory_iterator(sharded + "/out"))
    if (e.path().extension() == ".exr") shardNames.insert(e.path().filename());
  EXPECT_EQ(fullNames.size(), 12u);
  EXPECT_EQ(fullNames, shardNames);
  for (const std::string& name : fullNames)
    EXPECT_EQ(
        test::differingAovs(readExr(full + "/out/" + name), readExr(sharded + "/out/" + name)), "")
        << name;
  EXPECT_NE(runCommand(apertureBinary() + " batch --shard 3/3 " + quote(shardJob), &out), 0);
  EXPECT_NE(out.find("--shard: '3/3' must be K/N with 0 <= K < N"), std::string::npos) << out;
}

TEST(Batch, UnwritableOutputFailsOnlyThatCameraAndResumeRendersTheRest) {
  const std::string dir = scratchDir();
  json j = baseJob();
  j["cameras"] = json::parse(R"([
    {"name": "a", "eye": [0, 0, 5], "at": [0, 0, 0]},
    {"name": "blocked", "orbit": {"radius": 5}, "frames": 2},
    {"name": "c", "eye": [0, 3, 4], "at": [0, 0, 0]}
  ])");
  j["output"] = "{camera}/f_{frame}.exr";
  const std::string jobPath = writeJob(dir, j);
  writeFile(dir + "/blocked", "a regular file where a directory should be");
  std::string out;
  EXPECT_EQ(runCommand(apertureBinary() + " batch " + quote(jobPath), &out), 1) << out;
  EXPECT_NE(out.find("2 of 4 images failed: blocked frame 0, blocked frame 1"), std::string::npos)
      << out;
  EXPECT_TRUE(isCompleteExr(dir + "/a/f_0.exr"));
  EXPECT_TRUE(isCompleteExr(dir + "/c/f_0.exr"));
  json summary = readJson(dir + "/summary.json");
  EXPECT_EQ(summary["images_failed"], 2);
  EXPECT_EQ(summary["failed"], json({"blocked frame 0", "blocked frame 1"}));
  EXPECT_EQ(summary["images"][1]["status"], "failed");
  EXPECT_NE(summary["images"][1]["error"].get<std::string>().find("cannot create directory"),
            std::string::npos);

  // Fix the path; --resume renders only the two missing frames.
  fs::remove(dir + "/blocked");
  const auto before = fs::last_write_time(dir + "/a/f_0.exr");
  ASSERT_EQ(runCommand(apertureBinary() + " batch --resume " + quote(jobPath), &out), 0) << out;
  summary = readJson(dir + "/summary.json");
  EXPECT_EQ(summary["images_ok"], 2);
  EXPECT_EQ(summary["images_skipped"], 2);
  std::vector<std::string> statuses;
  for (const json& f : summary["images"]) statuses.push_back(f["status"]);
  EXPECT_EQ(statuses, (std::vector<std::string>{"skipped", "ok", "ok", "skipped"}));
  EXPECT_TRUE(isCompleteExr(dir + "/blocked/f_1.exr"));
  EXPECT_EQ(fs::last_write_time(dir + "/a/f_0.exr"), before);
}

TEST(Batch, InvalidJobsFailBeforeRenderingWithKeyAndReason) {
  const std::string dir = scratchDir();
  auto check = [&](json j, const std::string& expect) {
    const std::string jobPath = writeJob(dir, j);
    std::string out;
    const int rc = runCommand(apertureBinary() + " batch " + quote(jobPath), &out);
    EXPECT_NE(rc, 0) << out;
    EXPECT_NE(out.find(jobPath + ": " + expect), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir + "/out")) << expect;
    EXPECT_EQ(out.find("loaded"), std::string::npos) << "loaded a mesh for " << expect;
  };
  json j = baseJob();
  j["cameras"][0]["eyee"] = {0, 0, 1};
  check(j, "cameras[0].eyee: unknown key");
  j = baseJob();
  j["spp"] = "many";
  check(j, "spp: expected an integer, got a string");
  j = baseJob();
  j["size"] = {64, -48};
  check(j, "size: 64x-48: each component must be in [1, 65536] pixels");
  j = baseJob();
  j["scene"]["meshes"].push_back({{"path", "missing.obj"}});
  check(j, "scene.meshes[1].path: '" + dir + "/missing.obj': no such file");
  j = baseJob();
  j["cameras"][0]["dir"] = {0, 0, -1};
  j["cameras"][0].erase("at");
  j["cameras"][0]["up"] = {0, 0, 2};
  check(j, "cameras[0]: camera 'cam' frame 0: ");
  j = baseJob();
  j["output"] = "out/{frame}.exr";
  j["cameras"].push_back({{"name", "two"}, {"eye", {0, 0, 5}}, {"at", {0, 0, 0}}});
  check(j, "output: camera 'two' frame 0 and camera 'cam' frame 0 both write");
}

TEST(Batch, RepeatedMeshBecomesInstancesAndRendersLikeCopies) {
  const std::string dir = scratchDir();
  json j = baseJob();
  j["scene"]["meshes"] = json::parse(R"([
    {"path": "procedural:sphere?segments=48&rings=24",
     "transform": {"translate": [-1.5, 0, 0]}},
    {"path": "procedural:sphere?segments=48&rings=24",
     "transform": {"translate": [1.5, 0.2, 0], "rotate": {"axis": [0, 1, 0], "angle": 90},
                   "scale": [1, 0.8, 1]}}
  ])");
  j["cameras"][0] = {{"name", "v"}, {"eye", {0.2, 1, 6}}, {"at", {0, 0, 0}}, {"fov", 50}};
  j["size"] = {64, 40};
  j["aovs"] = "depth,normal,geomid";
  j["output"] = "inst/{camera}.exr";
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " batch " + quote(writeJob(dir, j)), &out), 0) << out;
  EXPECT_NE(out.find("2 instances"), std::string::npos) << out;
  EXPECT_EQ(readJson(dir + "/inst/summary.json")["instances"], 2);
  // The same placements as two distinct mesh specs: each baked at load, attached directly.
  j["scene"]["meshes"][1]["path"] = "procedural:sphere?rings=24&segments=48";
  j["output"] = "copies/{camera}.exr";
  ASSERT_EQ(runCommand(apertureBinary() + " batch " + quote(writeJob(dir, j)), &out), 0) << out;
  EXPECT_EQ(readJson(dir + "/copies/summary.json")["instances"], 0);

  test::expectSameGeometry(readExr(dir + "/inst/v.exr"), readExr(dir + "/copies/v.exr"), 201);
}

TEST(Batch, DryRunListsFramesAndWritesNothing) {
  const std::string dir = scratchDir();
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " batch --dry-run --shard 1/2 " +
                           quote(writeJob(dir, orbitJob())),
                       &out),
            0)
      << out;
  EXPECT_NE(out.find("12 images in the job, 6 in this shard, 6 to render"), std::string::npos)
      << out;
  EXPECT_NE(out.find("low_0001.exr"), std::string::npos);
  EXPECT_EQ(out.find("low_0000.exr"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir + "/out"));
}

TEST(Batch, SigintFinishesTheFrameInFlightAndLeavesOnlyCompleteFiles) {
  const std::string dir = scratchDir();
  json j = baseJob();
  j["cameras"][0] = {{"name", "t"}, {"orbit", {{"radius", 5}}}, {"frames", 3000}};
  const std::string jobPath = writeJob(dir, j);
  std::string out;
  // SIGINT once the first frame is written, so the handler is installed (a fixed delay is
  // too short on a loaded machine or under ThreadSanitizer, and a background job of sh starts
  // with SIGINT ignored, so an early signal would be lost).
  const int rc = runCommand("sh -c '" + apertureBinary() + " batch --quiet " + jobPath +
                                " & pid=$!; for i in $(seq 600); do ls " + dir +
                                "/out/*.exr >/dev/null 2>&1 && break; sleep 0.1; done; "
                                "kill -INT $pid; wait $pid'",
                            &out);
  EXPECT_EQ(rc, 130) << out;
  const json summary = readJson(dir + "/out/summary.json");
  const int ok = summary["images_ok"], interrupted = summary["images_interrupted"];
  EXPECT_GT(interrupted, 0);
  EXPECT_EQ(ok + interrupted, 3000);
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir + "/out")) {
    const std::string name = e.path().filename();
    if (name == "summary.json") continue;
    EXPECT_EQ(e.path().extension(), ".exr") << name;  // no temporary left behind
    EXPECT_TRUE(isCompleteExr(e.path().string())) << name;
    ++files;
  }
  EXPECT_EQ(files, ok);
}

namespace {

/// The pixels of a binary PPM preview ("P6\nW H\n255\n" then RGB bytes, as OpenImageIO
/// writes it), read without OpenImageIO; empty when the file is not such a PPM of W x H.
std::vector<uint8_t> readPpm(const std::string& path, int width, int height) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  int w = 0, h = 0, maxValue = 0;
  in >> magic >> w >> h >> maxValue;
  in.get();  // the one whitespace byte before the pixels
  EXPECT_EQ(magic, "P6") << path;
  EXPECT_EQ(w, width) << path;
  EXPECT_EQ(h, height) << path;
  EXPECT_EQ(maxValue, 255) << path;
  std::vector<uint8_t> rgb(size_t(width) * size_t(height) * 3);
  in.read(reinterpret_cast<char*>(rgb.data()), std::streamsize(rgb.size()));
  if (magic != "P6" || w != width || h != height || size_t(in.gcount()) != rgb.size()) return {};
  return rgb;
}

/// A turntable around three cubes (two instances of one spec, one baked), depth previews (PPM,
/// which the test reads without OpenImageIO).
json turntableJob() {
  return json::parse(R"({
    "scene": {"meshes": [
      {"path": "procedural:cube?size=2", "transform": {"translate": [1.5, 0, 0]}},
      {"path": "procedural:cube?size=2", "transform": {"translate": [-0.5, 0, 3]}},
      {"path": "procedural:cube?size=1", "transform": {"translate": [0, 2, -2]}}
    ]},
    "cameras": [{"name": "turn", "orbit": {"radius": 12, "height": 2}, "frames": 4, "fov": 40}],
    "aovs": "depth",
    "size": [48, 36],
    "output": "out/{camera}_{frame}.exr",
    "preview": "out/{camera}_{frame}.ppm",
    "performance": {"threads": 2}
  })");
}

/// The grey of depth z with NEAR -> 255 and FAR -> 0, clamped (docs/batch.md).
int greyOf(double z, const glm::dvec2& range) {
  const double t = std::min(1.0, std::max(0.0, (range.y - z) / (range.y - range.x)));
  return int(std::floor(255.0 * t + 0.5));
}

/// Checks the preview of `image` against its EXR: hits grey by `range` (within 1 for rounding),
/// misses the background. Returns how many hits are more than 2 greys off the mapping by the
/// image's own depth range (the convention a batch must not use).
int expectDepthPreview(const app::JobImage& image, const glm::dvec2& range) {
  SCOPED_TRACE(image.preview);
  const Framebuffer fb = readExr(image.output);
  const std::vector<uint8_t> rgb = readPpm(image.preview, fb.width, fb.height);
  if (rgb.empty()) return 0;
  float lo = INFINITY, hi = -INFINITY;
  for (float z : fb.depth)
    if (std::isfinite(z)) lo = std::min(lo, z), hi = std::max(hi, z);
  int hits = 0, offOwnRange = 0;
  for (size_t i = 0; i < fb.pixelCount(); ++i) {
    const uint8_t* p = &rgb[3 * i];
    if (!std::isfinite(fb.depth[i])) {
      EXPECT_EQ(
          std::vector<int>({p[0], p[1], p[2]}),
          std::vector<int>({kPreviewBackground[0], kPreviewBackground[1], kPreviewBackground[2]}))
          << "miss " << i;
      continue;
    }
    ++hits;
    EXPECT_EQ(p[0], p[1]);
    EXPECT_EQ(p[1], p[2]);
    EXPECT_LE(std::abs(p[0] - greyOf(fb.depth[i], range)), 1)
        << "pixel " << i << " depth " << fb.depth[i];
    offOwnRange += std::abs(p[0] - greyOf(fb.depth[i], glm::dvec2(lo, hi))) > 2;
  }
  EXPECT_GT(hits, 100);
  return offOwnRange;
}

}  // namespace

// Issue 10 item 6: every preview of a batch uses one depth range, so a turntable does not
// flicker: by default the planar depths of the scene's bounding box over all of the job's
// frames (shards agree), or the job's "preview_range".
TEST(Batch, TurntablePreviewsShareOneDepthRange) {
  const std::string dir = scratchDir();
  const std::string jobPath = writeJob(dir, turntableJob());
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet " + quote(jobPath), &out), 0) << out;
  const Job job = app::parseJob(jobPath);
  ASSERT_EQ(job.images.size(), 4u);

  // The scene's box from the placements: cubes of side 2 at (1.5, 0, 0) and (-0.5, 0, 3), of
  // side 1 at (0, 2, -2).
  const glm::dvec3 lo(-1.5, -1, -2.5), hi(2.5, 2.5, 4);
  glm::dvec2 range(INFINITY, -INFINITY);
  for (const app::JobImage& f : job.images) {
    const glm::dvec3 axis = glm::normalize(*f.params.at - f.params.eye);
    for (int k = 0; k < 8; ++k) {
      const glm::dvec3 corner(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
      const double z = glm::dot(corner - f.params.eye, axis);
      range = glm::dvec2(std::min(range.x, z), std::max(range.y, z));
    }
  }
  ASSERT_GT(range.x, 0.0);
  int offOwnRange = 0;
  for (const app::JobImage& f : job.images) offOwnRange += expectDepthPreview(f, range);
  EXPECT_GT(offOwnRange, 100) << "the frames' own ranges would give the same greys: the test "
                                 "could not tell a shared range from per-frame ones";

  // A shard renders only frames 1 and 3 but uses the range of the whole job.
  const std::string shardDir = dir + "/shard";
  fs::create_directories(shardDir);
  const std::string shardJob = writeJob(shardDir, turntableJob());
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet --shard 1/2 " + quote(shardJob), &out), 0)
      << out;
  for (int frame : {1, 3}) {
    const std::string name = "/out/turn_" + std::to_string(frame) + ".ppm";
    const std::vector<uint8_t> shardPixels = readPpm(shardDir + name, 48, 36);
    EXPECT_FALSE(shardPixels.empty());
    EXPECT_EQ(shardPixels, readPpm(dir + name, 48, 36)) << name;
  }

  // "preview_range" wins.
  json fixed = turntableJob();
  fixed["preview_range"] = {10, 13};
  const std::string fixedJob = writeJob(dir, fixed);
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet " + quote(fixedJob), &out), 0) << out;
  for (const app::JobImage& f : app::parseJob(fixedJob).images)
    expectDepthPreview(f, glm::dvec2(10, 13));
}

// A preview that cannot be written fails its frame and no EXR is written for it; the other
// frames are written with their previews.
TEST(Batch, APreviewThatFailsFailsItsFrameWithoutAnExr) {
  const std::string dir = scratchDir();
  json j = baseJob();
  j["cameras"] = json::parse(R"([
    {"name": "a", "eye": [0, 0, 5], "at": [0, 0, 0]},
    {"name": "blocked", "orbit": {"radius": 5}, "frames": 2}
  ])");
  j["output"] = "out/{camera}_{frame}.exr";
  j["preview"] = "previews/{camera}/{frame}.png";
  fs::create_directories(dir + "/previews");
  writeFile(dir + "/previews/blocked", "a regular file where a directory should be");
  std::string out;
  EXPECT_EQ(runCommand(apertureBinary() + " batch --quiet " + quote(writeJob(dir, j)), &out), 1)
      << out;
  EXPECT_TRUE(isCompleteExr(dir + "/out/a_0.exr"));
  EXPECT_TRUE(fs::exists(dir + "/previews/a/0.png"));
  EXPECT_FALSE(fs::exists(dir + "/out/blocked_0.exr"));
  EXPECT_FALSE(fs::exists(dir + "/out/blocked_1.exr"));
  const json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(summary["failed"], json({"blocked frame 0", "blocked frame 1"}));
  EXPECT_NE(summary["images"][1]["error"].get<std::string>().find(
                "preview: '" + dir + "/previews/blocked/0.png': cannot create directory"),
            std::string::npos)
      << summary["images"][1]["error"];
}

TEST(Batch, MaxMemoryCountsAFramebufferInEveryWriterThread) {
  // Framebuffers dominate this job (a 2000x2000 image of every AOV, a small mesh), so its
  // estimate is its render phase. With the writer threads overlapping the render, one
  // framebuffer renders, one waits and one is written by each writer thread; with --no-overlap
  // one exists. A limit between the two estimates refuses the first and accepts the second.
  const std::string dir = scratchDir();
  json j = baseJob();
  j["size"] = {2000, 2000};
  j["aovs"] = "all";
  j["performance"] = {{"threads", 2}};
  const std::string jobPath = writeJob(dir, j);
  const uint64_t pixels = 2000 * 2000;
  const uint64_t perPixel = framebufferBytesPerPixel(parseAovSet("all"));
  const int writers = app::writerThreadsFor(2, pixels * perPixel);
  ASSERT_EQ(writers, 2);  // 2000x2000 of every AOV is far below the 1 GiB the writers may hold
  const auto estimate = [&](int alive) {
    return estimateMemory({"procedural:sphere"}, pixels, 1, AovSet{}, perPixel * uint64_t(alive))
        .total();
  };
  const uint64_t overlapped = estimate(app::framebuffersAlive(writers));
  const uint64_t inline1 = estimate(app::framebuffersAlive(0));
  ASSERT_EQ(app::framebuffersAlive(writers), 4);
  ASSERT_GT(overlapped, inline1 + 3 * pixels * perPixel - 4096);
  const std::string limit = std::to_string((overlapped + inline1) / 2);
  std::string out;
  EXPECT_EQ(
      runCommand(apertureBinary() + " batch --dry-run --max-memory " + limit + " " + quote(jobPath),
                 &out),
      1)
      << out;
  EXPECT_NE(out.find("--max-memory"), std::string::npos) << out;
  EXPECT_EQ(runCommand(apertureBinary() + " batch --dry-run --no-overlap --max-memory " + limit +
                           " " + quote(jobPath),
                       &out),
            0)
      << out;
}
