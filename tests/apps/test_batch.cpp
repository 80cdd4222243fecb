// Batch rendering: job-file validation, camera paths, and `aperture batch` end to end (frames
// equal to `aperture render`, shards, failures and --resume, instancing).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "apps/job.h"
#include "core/error.h"
#include "core/exr.h"
#include "tests/support.h"

using namespace aperture;
using aperture::app::Job;
using aperture::app::parseJobText;
using aperture::test::apertureBinary;
using aperture::test::runCommand;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string quote(const std::string& s) { return "'" + s + "'"; }

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

json readJson(const std::string& path) {
  std::ifstream in(path);
  return json::parse(in);
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
  EXPECT_NE(msg.find("job.json: cameras[2].eyee: unknown key (known: name, type, eye"),
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
      {"/size", {-64, 48}, "size: [-64, 48]: width and height must be in [1, 65536]"},
      {"/size", "64x48", "size: expected [width, height], got a string"},
      {"/size", {64.5, 48}, "size[0]: expected an integer, got a number"},
      {"/spp", "4", "spp: expected an integer, got a string"},
      {"/spp", 0, "spp: 0: must be in [1, 65536]"},
      {"/half", 1, "half: expected true or false, got an integer"},
      {"/aovs", "colour", "aovs: "},
      {"/compression", "lzma", "compression: "},
      {"/performance", {{"packet", 3}}, "performance.packet: 3: must be 1, 4, 8 or 16"},
      {"/performance", {{"tile", 30}}, "performance.tile: 30: must be a multiple of 4"},
      {"/performance", {{"threads", -1}}, "performance.threads: -1: must be in [0, 4096]"},
      {"/performance", {{"bvh_quality", "best"}}, "performance.bvh_quality: "},
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
      {"/cameras", json::object(), "cameras: expected an array, got an object"},
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
  EXPECT_NE(parseError(j).find("camera 'cam' frame 0"), std::string::npos);
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
      {"out/{camera}.png", "the pattern must end in .exr"},
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
  check(j, "size: [64, -48]: width and height must be in [1, 65536]");
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
