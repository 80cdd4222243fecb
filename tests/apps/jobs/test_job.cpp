// Job files (apps/jobs/job.h): the example job, unknown keys, wrong types and ranges, missing
// meshes, degenerate cameras, output and preview patterns checked as the render flags are, and
// malformed input, each refused with the file, the JSON path and the reason; a camera's own
// size, spp and focus.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "apps/jobs/job.h"
#include "cameras/models/thinlens.h"
#include "core/exr/exr.h"
#include "core/util/error.h"
#include "tests/job_support.h"
#include "tests/support.h"
#include "tests/unwritable_dir.h"

using namespace aperture;
using aperture::app::Job;
using aperture::app::parseJobText;
using aperture::test::apertureBinary;
using aperture::test::baseJob;
using aperture::test::jobParseError;
using aperture::test::parseJobJson;
using aperture::test::quote;
using aperture::test::readJson;
using aperture::test::runCommand;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using nlohmann::json;
namespace fs = std::filesystem;

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
  const std::string msg = jobParseError(j);
  EXPECT_NE(msg.find("job.json: cameras[2].eyee: unknown key (did you mean 'eye'?) (known: name, "
                     "orbit, keyframes, frames, type, size, spp, eye"),
            std::string::npos)
      << msg;
  j = baseJob();
  j["scene"]["meshes"][0]["transform"] = {{"rotate", {{"axis", {0, 1, 0}}, {"angel", 3}}}};
  EXPECT_NE(jobParseError(j).find("scene.meshes[0].transform.rotate.angel: unknown key"),
            std::string::npos);
  j = baseJob();
  j["performance"] = {{"packets", 8}};
  EXPECT_NE(jobParseError(j).find("performance.packets: unknown key"), std::string::npos);
  j = baseJob();
  j["outptu"] = "x.exr";
  EXPECT_NE(jobParseError(j).find("job.json: outptu: unknown key"), std::string::npos);
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
    const std::string msg = jobParseError(j);
    EXPECT_NE(msg.find(std::string("job.json: ") + c.expect), std::string::npos)
        << c.pointer << " = " << c.value.dump() << "\n  got: " << msg;
  }
  json j = baseJob();
  j.erase("output");
  EXPECT_NE(jobParseError(j).find("output: required key is missing"), std::string::npos);
}

TEST(JobParse, MissingMeshFileIsNamedBeforeAnythingLoads) {
  const std::string dir = scratchDir();
  json j = baseJob();
  j["scene"]["meshes"] = {{{"path", "procedural:sphere"}}, {{"path", "nothere.ply"}}};
  const std::string msg = jobParseError(j, dir);
  EXPECT_NE(msg.find("scene.meshes[1].path: '" + dir + "/nothere.ply': no such file"),
            std::string::npos)
      << msg;
}

TEST(JobParse, GltfSceneChoosesTheSceneOfTheGltfMeshes) {
  const std::string dir = scratchDir();
  writeFile(dir + "/room.glb", "glb");  // existence is all a job checks before loading
  json j = baseJob();
  j["scene"]["meshes"] = {{{"path", "procedural:sphere"}}, {{"path", "room.glb"}}};
  EXPECT_FALSE(parseJobJson(j, dir).sceneSpec().gltfScene.has_value());
  j["scene"]["gltf_scene"] = 2;
  const Job job = parseJobJson(j, dir);
  EXPECT_EQ(job.gltfScene, 2);
  EXPECT_EQ(job.sceneSpec().gltfScene, 2);
  EXPECT_EQ(job.sceneSpec().meshes.at(1).spec, dir + "/room.glb");
  j["scene"]["gltf_scene"] = -1;
  std::string msg = jobParseError(j, dir);
  EXPECT_NE(msg.find("scene.gltf_scene: -1: must be >= 0"), std::string::npos) << msg;
  j["scene"]["gltf_scene"] = 0;
  j["scene"]["meshes"] = {{{"path", "procedural:sphere"}}};
  msg = jobParseError(j, dir);
  EXPECT_NE(msg.find("scene.gltf_scene: no mesh is a glTF file"), std::string::npos) << msg;
}

TEST(JobParse, DegenerateCamerasAreRejected) {
  json j = baseJob();
  j["cameras"][0]["up"] = {0, 0, 1};  // parallel to the view direction
  std::string msg = jobParseError(j);
  EXPECT_NE(msg.find("job.json: cameras[0]: camera 'cam' frame 0: "), std::string::npos) << msg;
  j = baseJob();
  j["cameras"][0]["fov"] = 180;
  EXPECT_NE(jobParseError(j).find("job.json: cameras[0].fov: 180: must be in (0, 180) degrees"),
            std::string::npos);
  j = baseJob();
  j["cameras"][0]["type"] = "pinhole";
  EXPECT_NE(jobParseError(j).find("unknown camera type 'pinhole'"), std::string::npos);
  j = baseJob();
  j["cameras"][0].erase("at");
  EXPECT_NE(jobParseError(j).find("cameras[0]: give exactly one of at and dir"), std::string::npos);
  // A zero-radius orbit, and a keyframe whose eye is its look-at point.
  j = baseJob();
  j["cameras"][0] = {{"name", "o"}, {"orbit", {{"radius", 0}}}, {"frames", 4}};
  EXPECT_NE(jobParseError(j).find("cameras[0].orbit.radius: 0: must be > 0"), std::string::npos);
  j["cameras"][0] = {{"name", "k"},
                     {"keyframes", {{{"frame", 0}, {"eye", {0, 0, 5}}, {"at", {0, 0, 5}}}}}};
  EXPECT_NE(jobParseError(j).find("camera 'k' frame 0"), std::string::npos);
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
    const std::string msg = jobParseError(j);
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
  EXPECT_NE(jobParseError(j).find("cameras[0].frames: 200000: must be in [1, 100000]"),
            std::string::npos);
}

// A camera entry may set its own size and spp over the job's; the images follow them.
TEST(JobParse, ACameraMaySetItsOwnSizeAndSpp) {
  json j = baseJob();
  j["cameras"].push_back(
      {{"name", "big"}, {"eye", {0, 0, 5}}, {"at", {0, 0, 0}}, {"size", {40, 30}}, {"spp", 4}});
  const Job job = parseJobJson(j);
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
  const Job job = parseJobJson(j);
  EXPECT_EQ(focusDistanceOf(job.images[0].params), 5.0);
  j["cameras"][0]["focus"] = 2.5;
  EXPECT_EQ(focusDistanceOf(parseJobJson(j).images[0].params), 2.5);
}

// Conflicting keys and keys of another model are refused naming both keys.
TEST(JobParse, ConflictingCameraKeysNameBothKeys) {
  json j = baseJob();
  j["cameras"][0]["focal_length"] = 35;
  const std::string msg = jobParseError(j);
  EXPECT_NE(msg.find("job.json: cameras[0]."), std::string::npos) << msg;
  EXPECT_NE(msg.find("cameras[0].fov"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cameras[0].focal_length"), std::string::npos) << msg;
  EXPECT_NE(msg.find("conflict"), std::string::npos) << msg;
  j = baseJob();
  j["cameras"][0]["fisheye_fov"] = 200;
  EXPECT_NE(jobParseError(j).find("cameras[0].fisheye_fov: does not apply to a 'perspective'"),
            std::string::npos)
      << jobParseError(j);
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
    const std::string message = jobParseError(job, dir);
    EXPECT_EQ(message.rfind("job.json: ", 0), 0u) << message;
    EXPECT_NE(message.find("job.json: " + expect), std::string::npos)
        << "expected '" << expect << "' in\n"
        << message;
  }

  j = withPreview("previews/{camera}.jpg");
  j["preview_range"] = {1, 9};
  const Job job = parseJobJson(j);
  ASSERT_TRUE(job.preview.depthRange);
  EXPECT_EQ(*job.preview.depthRange, glm::dvec2(1, 9));
  EXPECT_FALSE(parseJobJson(withPreview("p/{camera}.png")).preview.depthRange);

  APERTURE_REQUIRE_UNWRITABLE_DIR(ro, dir + "/ro");
  EXPECT_NE(
      jobParseError(withPreview("ro/{camera}.png"), dir)
          .find("job.json: preview: 'ro/{camera}.png': directory '" + dir + "/ro' is not writable"),
      std::string::npos)
      << jobParseError(withPreview("ro/{camera}.png"), dir);
}
