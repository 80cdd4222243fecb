// Batch rendering: job-file validation, camera paths, and `aperture batch` end to end (images
// equal to `aperture render`, shards (K/N, Slurm, Kubernetes) and merged summaries, failures,
// --resume (stale outputs, previews, temporaries), instancing).
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
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "apps/batch/batch_writer.h"
#include "apps/batch/resume.h"
#include "apps/batch/shard.h"
#include "apps/jobs/job.h"
#include "apps/services/limits.h"
#include "cameras/lenses/direction_table.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/exr/exr.h"
#include "core/io/image.h"
#include "core/util/error.h"
#include "tests/unwritable_dir.h"
#include "tests/support.h"

using namespace aperture;
using aperture::app::Job;
using aperture::app::parseJobText;
using aperture::test::apertureBinary;
using aperture::test::quote;
using aperture::test::readJson;
using aperture::test::runCommand;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

/// A valid job to start from: one fixed camera on a procedural sphere.
json baseJob() {
  return json::parse(R"({
    "scene": {"meshes": [{"path": "procedural:sphere"}]},
    "cameras": [{"name": "cam", "eye": [0, 0, 5], "at": [0, 0, 0], "fov": 40}],
    "size": [32, 24],
    "output": "out/{camera}_{frame:04d}.exr"
  })");
}

Job parse(const json& j, const std::string& baseDir = "") {
  return parseJobText(j.dump(), "job.json", baseDir);
}

/// The message parseJobText throws for `j` ("" if it does not throw).
std::string parseError(const json& j, const std::string& baseDir = "") {
  try {
    parse(j, baseDir);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string fmt(const glm::dvec3& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g", v.x, v.y, v.z);
  return buf;
}

/// Three orbit cameras with four frames each (different radius, elevation/height, up, fov).
json orbitJob() {
  json j = json::parse(R"({
    "scene": {"meshes": [{"path": "procedural:default?tris=20000"}]},
    "cameras": [
      {"name": "low", "orbit": {"centre": [0, 0, 0], "radius": 9, "height": 1.5}, "frames": 4,
       "fov": 45},
      {"name": "high", "orbit": {"centre": [0.5, 0, -0.5], "radius": 11, "elevation": 35,
       "start": 20}, "frames": 4, "fov": 35},
      {"name": "side", "orbit": {"centre": [0, 1, 0], "radius": 8, "height": 0.5, "sweep": 90},
       "frames": 4, "up": [0, 1, 0.1], "fov": 50}
    ],
    "aovs": "all",
    "size": [64, 48],
    "output": "out/{camera}_{frame:04d}.exr",
    "performance": {"threads": 2}
  })");
  return j;
}

std::string writeJob(const std::string& dir, const json& j) {
  const std::string path = dir + "/job.json";
  writeFile(path, j.dump(2));
  return path;
}

}  // namespace

TEST(JobParse, ExampleJobIsValid) {
  const std::string example = std::string(APERTURE_TESTS_DIR) + "/../docs/example-job.json";
  const Job job = app::parseJob(example);
  EXPECT_EQ(job.images.size(), 15u);
  EXPECT_EQ(job.meshes.size(), 4u);
  EXPECT_EQ(job.images[2].camera, "turntable");
  EXPECT_EQ(fs::path(job.images[2].output).filename(), "turntable_0000.exr");
}

TEST(JobParse, UnknownKeyNamesFileJsonPathAndKnownKeys) {
  json j = baseJob();
  j["cameras"].push_back({{"name", "b"}, {"eye", {0, 0, 5}}, {"at", {0, 0, 0}}});
  j["cameras"].push_back({{"name", "c"}, {"eyee", {0, 0, 5}}, {"at", {0, 0, 0}}});
  const std::string msg = parseError(j);
  EXPECT_NE(msg.find("job.json: cameras[2].eyee: unknown key (did you mean 'eye'?) (known: name, "
                     "orbit, keyframes, frames, type, size, spp, eye"),
            std::string::npos)
      << msg;
  j = baseJob();
  j["scene"]["meshes"][0]["transform"] = {{"rotate", {{"axis", {0, 1, 0}}, {"angel", 3}}}};
  EXPECT_NE(parseError(j).find("scene.meshes[0].transform.rotate.angel: unknown key"),
            std::string::npos);
  j = baseJob();
  j["performance"] = {{"packets", 8}};
  EXPECT_NE(parseError(j).find("performance.packets: unknown key"), std::string::npos);
  j = baseJob();
  j["outptu"] = "x.exr";
  EXPECT_NE(parseError(j).find("job.json: outptu: unknown key"), std::string::npos);
}

TEST(JobParse, WrongTypesAndRangesNameKeyAndReason) {
  struct Case {
    const char* pointer;
    json value;
    const char* expect;
  };
  const Case cases[] = {
      {"/size", {-64, 48}, "size: -64x48: each component must be in [1, 65536] pixels"},
      {"/size", "64x48", "size: expected [width, height], got a string"},
      {"/size", {64.5, 48}, "size[0]: expected an integer, got a number"},
      {"/spp", "4", "spp: expected an integer, got a string"},
      {"/spp", 0, "spp: 0: must be in [1, 65536]"},
      {"/half", 1, "half: expected true or false, got an integer"},
      {"/aovs", "colour", "aovs: "},
      {"/compression", "lzma", "compression: "},
      {"/performance", {{"packet", 3}}, "performance: packet width 3 is not one of 1, 4, 8, 16"},
      {"/performance",
       {{"tile", 30}},
       "performance: tile size 30 must be a multiple of 4 in [4, 4096]"},
      {"/performance", {{"threads", -1}}, "performance.threads: -1: must be in [0, 4096]"},
      {"/performance", {{"bvh_quality", "best"}}, "performance.bvh_quality: "},
      {"/performance",
       {{"bvh_chunk", 7}},
       "performance.bvh_chunk: bvh_chunk 7: must be 0 (one BVH per mesh) or at least 1024"},
      {"/performance", {{"bvh_chunk", -1}}, "performance.bvh_chunk: bvh_chunk -1: must be 0"},
      {"/cameras/0/eye", {0, 0}, "cameras[0].eye: expected an array of 3 numbers"},
      {"/cameras/0/eye", {0, "1", 0}, "cameras[0].eye[1]: expected a number, got a string"},
      {"/cameras/0/fov_axis", "z", "cameras[0].fov_axis: 'z' is not one of x, y, diagonal"},
      {"/cameras/0/name", "a b", "cameras[0].name: 'a b': use 1-128 letters"},
      {"/cameras/0/frames", 3, "cameras[0].frames: only a camera with orbit or keyframes"},
      {"/scene/meshes", json::array(), "scene.meshes: needs at least one mesh"},
      {"/scene/meshes/0/transform",
       {{"scale", 0}},
       "scene.meshes[0].transform.scale: scale must not be zero"},
      {"/scene/meshes/0/matrix",
       {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 1, 1}},
       "scene.meshes[0].matrix: the last row must be [0, 0, 0, 1]"},
      {"/cameras", 3, "cameras: expected an array, got an integer"},
      {"/cameras", json::object(), "cameras.from: required key is missing"},
      {"/cameras",
       {{"from", "x"}, {"image", 1}},
       "cameras.image: unknown key (did you mean 'images'?)"},
  };
  for (const Case& c : cases) {
    json j = baseJob();
    j[json::json_pointer(c.pointer)] = c.value;
    const std::string msg = parseError(j);
    EXPECT_NE(msg.find(std::string("job.json: ") + c.expect), std::string::npos)
        << c.pointer << " = " << c.value.dump() << "\n  got: " << msg;
  }
  json j = baseJob();
  j.erase("output");
  EXPECT_NE(parseError(j).find("output: required key is missing"), std::string::npos);
}

TEST(JobParse, MissingMeshFileIsNamedBeforeAnythingLoads) {
  const std::string dir = scratchDir();
  json j = baseJob();
  j["scene"]["meshes"] = {{{"path", "procedural:sphere"}}, {{"path", "nothere.ply"}}};
  const std::string msg = parseError(j, dir);
  EXPECT_NE(msg.find("scene.meshes[1].path: '" + dir + "/nothere.ply': no such file"),
            std::string::npos)
      << msg;
}

TEST(JobParse, DegenerateCamerasAreRejected) {
  json j = baseJob();
  j["cameras"][0]["up"] = {0, 0, 1};  // parallel to the view direction
  std::string msg = parseError(j);
  EXPECT_NE(msg.find("job.json: cameras[0]: camera 'cam' frame 0: "), std::string::npos) << msg;
  j = baseJob();
  j["cameras"][0]["fov"] = 180;
  EXPECT_NE(parseError(j).find("job.json: cameras[0].fov: 180: must be in (0, 180) degrees"),
            std::string::npos);
  j = baseJob();
  j["cameras"][0]["type"] = "pinhole";
  EXPECT_NE(parseError(j).find("unknown camera type 'pinhole'"), std::string::npos);
  j = baseJob();
  j["cameras"][0].erase("at");
  EXPECT_NE(parseError(j).find("cameras[0]: give exactly one of at and dir"), std::string::npos);
  // A zero-radius orbit, and a keyframe whose eye is its look-at point.
  j = baseJob();
  j["cameras"][0] = {{"name", "o"}, {"orbit", {{"radius", 0}}}, {"frames", 4}};
  EXPECT_NE(parseError(j).find("cameras[0].orbit.radius: 0: must be > 0"), std::string::npos);
  j["cameras"][0] = {{"name", "k"},
                     {"keyframes", {{{"frame", 0}, {"eye", {0, 0, 5}}, {"at", {0, 0, 5}}}}}};
  EXPECT_NE(parseError(j).find("camera 'k' frame 0"), std::string::npos);
}

TEST(JobParse, BadOutputPatterns) {
  const std::pair<const char*, const char*> cases[] = {
      {"out/{camera}_{frame:4d}.exr", "unknown placeholder '{frame:4d}'"},
      {"out/{cam}_{frame}.exr", "unknown placeholder '{cam}'"},
      {"out/{camera_{frame}.exr", "unknown placeholder"},
      {"out/{camera}_{frame.exr", "is not closed"},
      {"out/camera}.exr", "'}' without '{'"},
      {"out/{camera}.png", "'out/{camera}.png': unknown extension '.png'; supported: .exr"},
      {"out/fixed.exr", "both write"},
  };
  for (const auto& [pattern, expect] : cases) {
    json j = baseJob();
    j["cameras"].push_back({{"name", "two"}, {"eye", {0, 0, 5}}, {"at", {0, 0, 0}}});
    j["output"] = pattern;
    const std::string msg = parseError(j);
    EXPECT_NE(msg.find("job.json: output: "), std::string::npos) << pattern << ": " << msg;
    EXPECT_NE(msg.find(expect), std::string::npos) << pattern << ": " << msg;
  }
  EXPECT_EQ(app::expandOutputPattern("a/{camera}-{frame}-{frame:05d}.exr", "c", 42),
            "a/c-42-00042.exr");
}

TEST(JobParse, MalformedInputThrowsErrorNeverCrashes) {
  const std::string inputs[] = {
      "",
      "{",
      "[]",
      "null",
      "{\"scene\": ",
      std::string(10000, '['),
      "{\"size\": [1e999, 2]}",
      "{\"scene\": {\"meshes\": [{\"path\": 5}]}}",
      "\xff\xfe",
      "{\"cameras\": [[[]]]}",
      "{\"size\": [18446744073709551615, 1], \"output\": \"x.exr\"}",
  };
  for (const std::string& text : inputs) {
    try {
      parseJobText(text, "bad.json", "");
      ADD_FAILURE() << "accepted: " << text.substr(0, 40);
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("bad.json: ", 0), 0u) << e.what();
    }
  }
  json j = baseJob();
  j["cameras"][0] = {{"name", "o"}, {"orbit", {{"radius", 1}}}, {"frames", 200000}};
  EXPECT_NE(parseError(j).find("cameras[0].frames: 200000: must be in [1, 100000]"),
            std::string::npos);
}

TEST(JobPaths, OrbitEyesMatchHandComputedPositions) {
  json j = baseJob();
  // Up +Y: frame k sits at azimuth start + sweep * k / frames, measured from +Z towards +X.
  j["cameras"][0] = {
      {"name", "o"},
      {"orbit", {{"centre", {1, 2, 3}}, {"radius", 4}, {"height", 0.5}, {"start", 90}}},
      {"frames", 4}};
  // Elevation 30 degrees at distance 2, up +Z: the reference direction becomes +X.
  j["cameras"].push_back({{"name", "e"},
                          {"orbit", {{"radius", 2}, {"elevation", 30}, {"sweep", 180}}},
                          {"frames", 2},
                          {"up", {0, 0, 1}}});
  const Job job = parse(j);
  ASSERT_EQ(job.images.size(), 6u);
  auto expectEye = [&](size_t index, glm::dvec3 expected) {
    const glm::dvec3 eye = job.images[index].params.eye;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(eye[c], expected[c], 1e-12) << index << " axis " << c;
  };
  expectEye(0, {5, 2.5, 3});             // 90 degrees: +X
  expectEye(1, {1, 2.5, -1});            // 180 degrees: -Z
  expectEye(2, {-3, 2.5, 3});            // 270 degrees: -X
  expectEye(3, {1, 2.5, 7});             // 360 degrees: +Z
  expectEye(4, {std::sqrt(3.0), 0, 1});  // azimuth 0 along +X, raised 30 degrees along +Z
  expectEye(5, {0, std::sqrt(3.0), 1});  // azimuth 90: +Y (= up x X)
  EXPECT_EQ(job.images[1].params.at.value(), glm::dvec3(1, 2, 3));
  EXPECT_EQ(job.images[1].camera, "o");
  EXPECT_EQ(job.images[1].frame, 1);
  EXPECT_EQ(job.images[4].index, 4u);
}

TEST(JobPaths, KeyframesInterpolateLinearlyAndHoldAtTheEnds) {
  json j = baseJob();
  j["cameras"][0] = {
      {"name", "k"},
      {"frames", 7},
      {"keyframes",
       {{{"frame", 1}, {"eye", {0, 0, 10}}, {"at", {0, 0, 0}}, {"fov", 40}},
        {{"frame", 5}, {"eye", {8, 4, 10}}, {"at", {0, 2, 0}}, {"up", {0, 1, 0.4}}, {"fov", 60}}}}};
  const Job job = parse(j);
  ASSERT_EQ(job.images.size(), 7u);
  auto near = [](glm::dvec3 a, glm::dvec3 b) { return glm::length(a - b) < 1e-12; };
  const CameraParams& f0 = job.images[0].params;  // before the first keyframe: held
  EXPECT_TRUE(near(f0.eye, {0, 0, 10}));
  EXPECT_DOUBLE_EQ(*f0.fovDeg, 40);
  const CameraParams& f2 = job.images[2].params;  // t = 1/4
  EXPECT_TRUE(near(f2.eye, {2, 1, 10}));
  EXPECT_TRUE(near(*f2.at, {0, 0.5, 0}));
  EXPECT_TRUE(near(f2.up, {0, 1, 0.1}));
  EXPECT_NEAR(*f2.fovDeg, 45, 1e-12);
  const CameraParams& f4 = job.images[4].params;  // t = 3/4
  EXPECT_TRUE(near(f4.eye, {6, 3, 10}));
  EXPECT_NEAR(*f4.fovDeg, 55, 1e-12);
  const CameraParams& f6 = job.images[6].params;  // after the last keyframe: held
  EXPECT_TRUE(near(f6.eye, {8, 4, 10}));
  EXPECT_NEAR(*f6.fovDeg, 60, 1e-12);
  // Keyframes must ascend.
  j["cameras"][0]["keyframes"][1]["frame"] = 1;
  EXPECT_NE(parseError(j).find("cameras[0].keyframes[1].frame: 1: keyframes must ascend"),
            std::string::npos);
}

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
    const std::string cmd =
        apertureBinary() + " render --quiet --mesh 'procedural:default?tris=20000' --size 64,48" +
        " --aov all --threads 2 --eye " + fmt(p.eye) + " --at " + fmt(*p.at) + " --up " +
        fmt(p.up) + " --fov " + std::to_string(int(*p.fovDeg)) + " --out " + quote(single);
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

// A camera entry may set its own size and spp over the job's; the images follow them.
TEST(JobParse, ACameraMaySetItsOwnSizeAndSpp) {
  json j = baseJob();
  j["cameras"].push_back(
      {{"name", "big"}, {"eye", {0, 0, 5}}, {"at", {0, 0, 0}}, {"size", {40, 30}}, {"spp", 4}});
  const Job job = parse(j);
  ASSERT_EQ(job.images.size(), 2u);
  EXPECT_EQ(job.images[0].params.width, 32);
  EXPECT_EQ(job.images[0].params.height, 24);
  EXPECT_EQ(job.images[0].params.spp, 1);
  EXPECT_EQ(job.images[1].params.width, 40);
  EXPECT_EQ(job.images[1].params.height, 30);
  EXPECT_EQ(job.images[1].params.spp, 4);
}

// The thin lens focuses at |at − eye| unless told otherwise.
TEST(JobParse, ThinLensFocusDefaultsToTheLookAtDistance) {
  json j = baseJob();
  j["cameras"][0]["type"] = "thinlens";
  j["cameras"][0]["aperture"] = 0.1;
  j["cameras"][0]["eye"] = {0, 3, 4};
  const Job job = parse(j);
  EXPECT_EQ(focusDistanceOf(job.images[0].params), 5.0);
  j["cameras"][0]["focus"] = 2.5;
  EXPECT_EQ(focusDistanceOf(parse(j).images[0].params), 2.5);
}

// Conflicting keys and keys of another model are refused naming both keys.
TEST(JobParse, ConflictingCameraKeysNameBothKeys) {
  json j = baseJob();
  j["cameras"][0]["focal_length"] = 35;
  const std::string msg = parseError(j);
  EXPECT_NE(msg.find("job.json: cameras[0]."), std::string::npos) << msg;
  EXPECT_NE(msg.find("cameras[0].fov"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cameras[0].focal_length"), std::string::npos) << msg;
  EXPECT_NE(msg.find("conflict"), std::string::npos) << msg;
  j = baseJob();
  j["cameras"][0]["fisheye_fov"] = 200;
  EXPECT_NE(parseError(j).find("cameras[0].fisheye_fov: does not apply to a 'perspective'"),
            std::string::npos)
      << parseError(j);
}

TEST(JobParse, BatchImagesHaveTheirCameraSize) {
  const std::string dir = test::scratchDir();
  json j = baseJob();
  j["cameras"].push_back(
      {{"name", "big"}, {"eye", {0, 0, 5}}, {"at", {0, 0, 0}}, {"size", {40, 30}}});
  j["aovs"] = "depth";
  test::writeFile(dir + "/job.json", j.dump());
  std::string log;
  ASSERT_EQ(test::runCommand(test::apertureBinary() + " batch --quiet " + dir + "/job.json", &log),
            0)
      << log;
  EXPECT_EQ(readExr(dir + "/out/cam_0000.exr").width, 32);
  const Framebuffer big = readExr(dir + "/out/big_0000.exr");
  EXPECT_EQ(big.width, 40);
  EXPECT_EQ(big.height, 30);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// --resume: outputs are kept only when they match the job; temporaries of dead processes go.

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

/// The status of each image in a summary, by index.
std::map<size_t, std::string> statuses(const json& summary) {
  std::map<size_t, std::string> s;
  for (const json& e : summary["images"]) s[e["index"].get<size_t>()] = e["status"];
  return s;
}

/// The indices whose status is `status`.
std::set<size_t> withStatus(const json& summary, const std::string& status) {
  std::set<size_t> s;
  for (const auto& [index, st] : statuses(summary))
    if (st == status) s.insert(index);
  return s;
}

/// Runs `aperture batch ARGS JOB`; returns the exit code, output in *out.
int batch(const std::string& args, const std::string& jobPath, std::string* out) {
  return runCommand(apertureBinary() + " batch " + args + " " + quote(jobPath), out);
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
  ASSERT_EQ(batch("--quiet", jobPath, &out), 0) << out;
  EXPECT_EQ(readJson(dir + "/out/summary.json")["images_ok"], 7);
  ASSERT_EQ(batch("--resume", jobPath, &out), 0) << out;
  const json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(withStatus(summary, "skipped").size(), 7u) << out;
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
  ASSERT_EQ(batch("--quiet", jobPath, &out), 0) << out;
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
  ASSERT_EQ(batch("--quiet", jobPath, &out), 0) << out;
  const Job job = app::parseJob(jobPath);
  ASSERT_EQ(job.images.size(), 7u);

  // Index 0: an EXR of another size at its path (the same camera rendered at 40x24).
  const CameraParams& p0 = job.images[0].params;
  ASSERT_EQ(runCommand(apertureBinary() + " render --quiet --mesh procedural:sphere --size 40,24" +
                           " --spp 2 --aov color,depth,primid --eye " + fmt(p0.eye) + " --at " +
                           fmt(*p0.at) + " --fov 40 --out " + quote(job.images[0].output),
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

  ASSERT_EQ(batch("--resume", jobPath, &out), 0) << out;
  const json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(withStatus(summary, "ok"), (std::set<size_t>{0, 1, 3, 4, 5, 6})) << out;
  EXPECT_EQ(withStatus(summary, "skipped"), (std::set<size_t>{2})) << out;
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
  ASSERT_EQ(batch("--resume --quiet", jobPath, &out), 0) << out;
  EXPECT_EQ(withStatus(readJson(dir + "/out/summary.json"), "skipped").size(), 7u);
  EXPECT_TRUE(isCompleteExr(job.images[1].output));
}

TEST(BatchResume, ChangedSizeOrAovsInTheJobRenderEverythingAgain) {
  const std::string dir = scratchDir();
  json j = resumeJob();
  const std::string jobPath = writeJob(dir, j);
  std::string out;
  ASSERT_EQ(batch("--quiet", jobPath, &out), 0) << out;
  j["size"] = {40, 24};
  writeJob(dir, j);
  ASSERT_EQ(batch("--resume --quiet", jobPath, &out), 0) << out;
  json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(withStatus(summary, "ok").size(), 7u);
  EXPECT_EQ(staleReasonOf(summary, 5), "size 32x24, job wants 40x24");
  EXPECT_EQ(readExrHeader(app::parseJob(jobPath).images[5].output).width, 40);

  j["aovs"] = "color,depth";  // primID dropped
  writeJob(dir, j);
  ASSERT_EQ(batch("--resume --quiet", jobPath, &out), 0) << out;
  summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(withStatus(summary, "ok").size(), 7u);
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
  EXPECT_EQ(batch("", jobPath, &out), 1) << out;
  EXPECT_NE(out.find("1 of 7 images failed: ortho frame 0"), std::string::npos) << out;
  json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(summary["images_failed"], 1);
  EXPECT_EQ(summary["failed"], json({"ortho frame 0"}));
  EXPECT_EQ(withStatus(summary, "failed"), (std::set<size_t>{1}));
  EXPECT_NE(summary["images"][1]["error"].get<std::string>().find("preview"), std::string::npos);

  // The preview is written first, so its failure left no EXR: --resume renders that image
  // again, exit 0.
  const Job job = app::parseJob(jobPath);
  EXPECT_FALSE(fs::exists(job.images[1].output));
  fs::remove(dir + "/prev/ortho");
  ASSERT_EQ(batch("--resume --quiet", jobPath, &out), 0) << out;
  summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(withStatus(summary, "ok"), (std::set<size_t>{1}));
  EXPECT_EQ(withStatus(summary, "skipped").size(), 6u);
  EXPECT_TRUE(fs::exists(job.images[1].preview));
}

TEST(BatchResume, TemporariesOfDeadProcessesAreRemovedThoseOfLiveOnesKept) {
  const std::string dir = scratchDir();
  const std::string jobPath = writeJob(dir, resumeJob());
  std::string out;
  ASSERT_EQ(batch("--quiet", jobPath, &out), 0) << out;
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

  ASSERT_EQ(batch("--resume", jobPath, &out), 0) << out;
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
  EXPECT_EQ(withStatus(summary, "skipped").size(), 7u);
  // Without --resume nothing is swept.
  writeFile(deadExr, "partial");
  ASSERT_EQ(batch("--quiet", jobPath, &out), 0) << out;
  EXPECT_TRUE(fs::exists(deadExr));
}

// ---------------------------------------------------------------------------------------------
// Shards from a scheduler's environment, and merging the shards' summaries.

namespace {

/// A fake environment for parseShard.
app::EnvironmentLookup fakeEnvironment(const std::map<std::string, std::string>& vars) {
  return [vars](const char* name) -> const char* {
    auto it = vars.find(name);
    return it == vars.end() ? nullptr : it->second.c_str();
  };
}

/// The message parseShard throws ("" if it does not).
std::string shardError(const std::string& spec, const std::map<std::string, std::string>& vars) {
  try {
    app::parseShard(spec, fakeEnvironment(vars));
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// Runs every shard of `j` in `dir` with `envFor(k)` before the command and `--shard spec`;
/// returns how often each image index was rendered ok, and checks each shard's summary name.
std::map<size_t, int> runShards(const std::string& dir, const json& j, const std::string& spec,
                                size_t n, const std::function<std::string(size_t)>& envFor) {
  fs::create_directories(dir);
  const std::string jobPath = writeJob(dir, j);
  std::map<size_t, int> rendered;
  for (size_t k = 0; k < n; ++k) {
    std::string out;
    const std::string cmd = "env " + envFor(k) + " " + apertureBinary() +
                            " batch --quiet --shard " + spec + " " + quote(jobPath);
    EXPECT_EQ(runCommand(cmd, &out), 0) << cmd << "\n" << out;
    const std::string summaryPath =
        dir + "/out/summary.shard-" + std::to_string(k) + "-of-" + std::to_string(n) + ".json";
    if (!fs::exists(summaryPath)) {
      ADD_FAILURE() << "no " << summaryPath << " after " << cmd << "\n" << out;
      continue;
    }
    for (size_t index : withStatus(readJson(summaryPath), "ok")) ++rendered[index];
  }
  return rendered;
}

/// "camera frame N" of every image of the job whose index is k modulo n.
std::vector<std::string> labelsOfShard(const Job& job, size_t k, size_t n) {
  std::vector<std::string> labels;
  for (const app::JobImage& image : job.images)
    if (image.index % n == k)
      labels.push_back(image.camera + " frame " + std::to_string(image.frame));
  return labels;
}

}  // namespace

TEST(BatchShard, SlurmVariablesGiveKAndNOrANamedError) {
  using Vars = std::map<std::string, std::string>;
  // --array=1-3: tasks 1, 2, 3 are shards 0, 1, 2 of 3.
  for (size_t id = 1; id <= 3; ++id) {
    const app::Shard s =
        app::parseShard("slurm", fakeEnvironment({{"SLURM_ARRAY_TASK_ID", std::to_string(id)},
                                                  {"SLURM_ARRAY_TASK_MIN", "1"},
                                                  {"SLURM_ARRAY_TASK_MAX", "3"},
                                                  {"SLURM_ARRAY_TASK_COUNT", "3"}}));
    EXPECT_EQ(s.k, id - 1);
    EXPECT_EQ(s.n, 3u);
  }
  // --array=4-12:4: tasks 4, 8, 12 are shards 0, 1, 2 of 3 (K is not ID - MIN).
  const Vars stepped = {{"SLURM_ARRAY_TASK_ID", "8"},
                        {"SLURM_ARRAY_TASK_MIN", "4"},
                        {"SLURM_ARRAY_TASK_MAX", "12"},
                        {"SLURM_ARRAY_TASK_STEP", "4"},
                        {"SLURM_ARRAY_TASK_COUNT", "3"}};
  EXPECT_EQ(app::parseShard("slurm", fakeEnvironment(stepped)).k, 1u);

  const Vars base = {
      {"SLURM_ARRAY_TASK_ID", "2"}, {"SLURM_ARRAY_TASK_MIN", "1"}, {"SLURM_ARRAY_TASK_COUNT", "3"}};
  for (const char* missing :
       {"SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_COUNT"}) {
    Vars v = base;
    v.erase(missing);
    EXPECT_NE(shardError("slurm", v).find(std::string(missing) + " is not set"), std::string::npos)
        << shardError("slurm", v);
  }
  Vars v = base;
  v["SLURM_ARRAY_TASK_COUNT"] = "three";
  EXPECT_NE(shardError("slurm", v).find("SLURM_ARRAY_TASK_COUNT='three' is not a number"),
            std::string::npos);
  v = base;
  v["SLURM_ARRAY_TASK_ID"] = "4";  // past the three tasks 1..3
  EXPECT_NE(shardError("slurm", v)
                .find("task 4 is not one of the 3 tasks of the array "
                      "(SLURM_ARRAY_TASK_ID=4, SLURM_ARRAY_TASK_MIN=1"),
            std::string::npos)
      << shardError("slurm", v);
  v = base;
  v["SLURM_ARRAY_TASK_ID"] = "0";  // below MIN
  EXPECT_NE(shardError("slurm", v).find("task 0 is not one of the 3 tasks"), std::string::npos);
  v = base;
  v["SLURM_ARRAY_TASK_MAX"] = "9";  // --array=1,2,9: not a range
  EXPECT_NE(shardError("slurm", v).find("the array is not a range first-last[:step]"),
            std::string::npos)
      << shardError("slurm", v);
}

TEST(BatchShard, KubernetesIndexAndPlainKOverN) {
  for (size_t index = 0; index < 4; ++index) {
    const app::Shard s = app::parseShard(
        "k8s/4", fakeEnvironment({{"JOB_COMPLETION_INDEX", std::to_string(index)}}));
    EXPECT_EQ(s.k, index);
    EXPECT_EQ(s.n, 4u);
  }
  EXPECT_NE(shardError("k8s/4", {{"JOB_COMPLETION_INDEX", "4"}})
                .find("JOB_COMPLETION_INDEX=4 is not below N = 4"),
            std::string::npos);
  EXPECT_NE(shardError("k8s/4", {}).find("JOB_COMPLETION_INDEX is not set"), std::string::npos);
  EXPECT_NE(shardError("k8s", {{"JOB_COMPLETION_INDEX", "0"}}).find("k8s/N"), std::string::npos);
  EXPECT_NE(shardError("k8s/0", {{"JOB_COMPLETION_INDEX", "0"}}).find("k8s/N"), std::string::npos);
  // K/N does not read the environment.
  const app::Shard s = app::parseShard("2/5", fakeEnvironment({{"JOB_COMPLETION_INDEX", "0"}}));
  EXPECT_EQ(s.k, 2u);
  EXPECT_EQ(s.n, 5u);
  EXPECT_NE(shardError("5/5", {}).find("--shard: '5/5' must be K/N"), std::string::npos);
  EXPECT_NE(shardError("slurm/3", {}).find("must be K/N"), std::string::npos);
}

TEST(BatchShard, SlurmAndKubernetesShardsRenderEveryImageExactlyOnce) {
  const std::string dir = scratchDir();
  json j = orbitJob();
  j["size"] = {24, 16};
  j["aovs"] = "depth";
  // Slurm --array=1-3 (MIN 1, COUNT 3): tasks 1, 2, 3.
  const std::map<size_t, int> slurm = runShards(dir + "/slurm", j, "slurm", 3, [](size_t k) {
    return "SLURM_ARRAY_TASK_ID=" + std::to_string(k + 1) +
           " SLURM_ARRAY_TASK_MIN=1 SLURM_ARRAY_TASK_MAX=3 SLURM_ARRAY_TASK_COUNT=3";
  });
  // A Kubernetes indexed Job of 5 completions: indices 0..4.
  const std::map<size_t, int> k8s = runShards(dir + "/k8s", j, "k8s/5", 5, [](size_t k) {
    return "JOB_COMPLETION_INDEX=" + std::to_string(k);
  });
  for (const auto* rendered : {&slurm, &k8s}) {
    EXPECT_EQ(rendered->size(), 12u);
    for (const auto& [index, times] : *rendered) {
      EXPECT_LT(index, 12u);
      EXPECT_EQ(times, 1) << "image " << index;
    }
  }
  // The Slurm shard with task 2 is shard 1: images 1, 4, 7, 10.
  const json shard1 = readJson(dir + "/slurm/out/summary.shard-1-of-3.json");
  EXPECT_EQ(withStatus(shard1, "ok"), (std::set<size_t>{1, 4, 7, 10}));
  EXPECT_NE(shard1["shard"]["from"].get<std::string>().find("SLURM_ARRAY_TASK_ID=2"),
            std::string::npos);
  // Inside an array task without --shard: a note, and every image.
  std::string out;
  ASSERT_EQ(runCommand("env SLURM_ARRAY_TASK_ID=2 " + apertureBinary() + " batch --dry-run " +
                           quote(dir + "/slurm/job.json"),
                       &out),
            0);
  EXPECT_NE(out.find("SLURM_ARRAY_TASK_ID=2 but no --shard"), std::string::npos) << out;
  EXPECT_NE(out.find("12 images in the job, 12 in this shard"), std::string::npos) << out;
}

TEST(BatchShard, MergedSummariesNameTheMissingImages) {
  const std::string dir = scratchDir();
  json j = orbitJob();
  j["size"] = {24, 16};
  j["aovs"] = "depth";
  runShards(dir, j, "slurm", 3, [](size_t k) {
    return "SLURM_ARRAY_TASK_ID=" + std::to_string(k + 1) +
           " SLURM_ARRAY_TASK_MIN=1 SLURM_ARRAY_TASK_COUNT=3";
  });
  const Job job = app::parseJob(dir + "/job.json");
  auto shardSummary = [&](int k) {
    return quote(dir + "/out/summary.shard-" + std::to_string(k) + "-of-3.json");
  };
  const std::string merged = dir + "/merged/all.json";
  std::string out;
  // Shards 0 and 2 only: shard 1's images are missing, named from the job file.
  EXPECT_EQ(runCommand(apertureBinary() + " batch --merge-summaries " + quote(merged) + " " +
                           shardSummary(0) + " " + shardSummary(2),
                       &out),
            1)
      << out;
  json m = readJson(merged);
  const std::vector<std::string> expectMissing = labelsOfShard(job, 1, 3);
  ASSERT_EQ(expectMissing.size(), 4u);
  EXPECT_EQ(m["missing"], json(expectMissing));
  EXPECT_EQ(m["images_missing"], 4);
  EXPECT_EQ(m["images_ok"], 8);
  EXPECT_EQ(m["images_in_job"], 12);
  EXPECT_EQ(m["images"].size(), 12u);
  EXPECT_EQ(m["images"][1]["status"], "missing");
  EXPECT_EQ(m["images"][1]["output"], job.images[1].output);
  EXPECT_NE(out.find("4 of 12 images missing (no summary has them ok): " + expectMissing[0] + ", " +
                     expectMissing[1]),
            std::string::npos)
      << out;

  // All three: complete, exit 0; the entries keep the shard that rendered them.
  ASSERT_EQ(runCommand(apertureBinary() + " batch --merge-summaries " + quote(merged) + " " +
                           shardSummary(0) + " " + shardSummary(1) + " " + shardSummary(2),
                       &out),
            0)
      << out;
  m = readJson(merged);
  EXPECT_EQ(m["images_missing"], 0);
  EXPECT_EQ(m["missing"], json::array());
  EXPECT_EQ(m["images_ok"], 12);
  for (size_t index = 0; index < 12; ++index) {
    EXPECT_EQ(m["images"][index]["index"], index);
    EXPECT_EQ(m["images"][index]["summary"],
              dir + "/out/summary.shard-" + std::to_string(index % 3) + "-of-3.json");
  }
}

TEST(BatchShard, MergeRefusesSummariesOfDifferentJobs) {
  const std::string dir = scratchDir();
  json a = baseJob(), b = baseJob();
  b["output"] = "other/{camera}.exr";
  fs::create_directories(dir + "/a");
  fs::create_directories(dir + "/b");
  std::string out;
  ASSERT_EQ(batch("--quiet", writeJob(dir + "/a", a), &out), 0) << out;
  ASSERT_EQ(batch("--quiet", writeJob(dir + "/b", b), &out), 0) << out;
  const std::string first = dir + "/a/out/summary.json", second = dir + "/b/other/summary.json";
  EXPECT_EQ(runCommand(apertureBinary() + " batch --merge-summaries " + quote(dir + "/x.json") +
                           " " + quote(first) + " " + quote(second),
                       &out),
            1);
  EXPECT_NE(out.find("'" + first + "' and '" + second + "' are summaries of different jobs (\"" +
                     dir + "/a/job.json\" and \"" + dir + "/b/job.json\")"),
            std::string::npos)
      << out;
  EXPECT_FALSE(fs::exists(dir + "/x.json"));
  // The same job twice merges (a re-run's summary beside the first).
  EXPECT_EQ(runCommand(apertureBinary() + " batch --merge-summaries " + quote(dir + "/x.json") +
                           " " + quote(first) + " " + quote(first),
                       &out),
            0)
      << out;
  EXPECT_EQ(readJson(dir + "/x.json")["images_ok"], 1);
}

// Issue 10 item 5 in job files: the "output" and "preview" patterns, their directories up to the
// first placeholder, every frame's paths, the AOVs a preview needs and "preview_range" are
// checked as `aperture render` checks its flags, naming the key and the value.
TEST(JobParse, OutputsAreCheckedLikeTheRenderFlags) {
  const std::string dir = scratchDir();
  writeFile(dir + "/afile", "a regular file");
  fs::create_directories(dir + "/out/cam_0000.exr");
  auto withPreview = [](const char* pattern) {
    json j = baseJob();
    j["preview"] = pattern;
    return j;
  };
  std::vector<std::pair<json, std::string>> cases;
  cases.emplace_back(withPreview("out/{camera}.gif"),
                     "preview: 'out/{camera}.gif': unknown extension '.gif'; supported: .png");
  cases.emplace_back(withPreview("out/{camera}"), "preview: 'out/{camera}': has no extension");
  json j = withPreview("out/{camera}.png");
  j["aovs"] = "position,distance";
  cases.emplace_back(j,
                     "preview: 'out/{camera}.png': none of the AOVs distance,position can be "
                     "previewed");
  j = withPreview("out/{camera}.png");
  j["preview_range"] = {5, 2};
  cases.emplace_back(j, "preview_range: [5, 2]: NEAR 5 must be less than FAR 2");
  j["preview_range"] = {-1, 2};
  cases.emplace_back(j, "preview_range: [-1, 2]: NEAR -1 must be >= 0");
  j["preview_range"] = {1};
  cases.emplace_back(j, "preview_range: expected an array of 2 numbers");
  j = baseJob();
  j["preview_range"] = {1, 2};
  cases.emplace_back(j, "preview_range: needs a \"preview\" pattern");
  j = baseJob();
  j["output"] = "afile/{camera}_{frame}.exr";
  cases.emplace_back(j, "output: 'afile/{camera}_{frame}.exr': cannot create directory '" + dir +
                            "/afile': '" + dir + "/afile' is not a directory");
  j = withPreview("afile/p/{camera}.png");
  cases.emplace_back(j, "preview: 'afile/p/{camera}.png': cannot create directory");
  j = baseJob();  // out/{camera}_{frame:04d}.exr: frame 0 of "cam" is a directory
  cases.emplace_back(j, "output: '" + dir + "/out/cam_0000.exr': is a directory");
  for (const auto& [job, expect] : cases) {
    const std::string message = parseError(job, dir);
    EXPECT_EQ(message.rfind("job.json: ", 0), 0u) << message;
    EXPECT_NE(message.find("job.json: " + expect), std::string::npos)
        << "expected '" << expect << "' in\n"
        << message;
  }

  j = withPreview("previews/{camera}.jpg");
  j["preview_range"] = {1, 9};
  const Job job = parse(j);
  ASSERT_TRUE(job.preview.depthRange);
  EXPECT_EQ(*job.preview.depthRange, glm::dvec2(1, 9));
  EXPECT_FALSE(parse(withPreview("p/{camera}.png")).preview.depthRange);

  APERTURE_REQUIRE_UNWRITABLE_DIR(ro, dir + "/ro");
  EXPECT_NE(
      parseError(withPreview("ro/{camera}.png"), dir)
          .find("job.json: preview: 'ro/{camera}.png': directory '" + dir + "/ro' is not writable"),
      std::string::npos)
      << parseError(withPreview("ro/{camera}.png"), dir);
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
