// Batch jobs of several scenes ("scenes", docs/batch.md): the job form (merging, {scene},
// errors naming the JSON path), the load-ahead pipeline (scene k+1 loads while scene k
// renders, at most two scenes alive), and `aperture batch` end to end: the images of a
// many-scene job are those of K separate one-scene runs, bit for bit, also with --shard and
// --resume.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/batch/scene_pipeline.h"
#include "apps/jobs/job.h"
#include "apps/services/limits.h"
#include "core/exr/exr.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;
using aperture::test::apertureBinary;
using aperture::test::quote;
using aperture::test::readJson;
using aperture::test::runCommand;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

/// Three scenes of different procedural meshes: the first two use the shared cameras, the
/// third its own cameras and its own size (an entry's keys win over the shared ones).
json scenesJob() {
  return json::parse(R"({
    "scenes": [
      {"name": "small", "scene": {"meshes": [{"path": "procedural:spheres?tris=3000"}]}},
      {"name": "large", "scene": {"meshes": [{"path": "procedural:spheres?tris=20000"}]}},
      {"name": "ball", "scene": {"meshes": [{"path": "procedural:sphere?radius=2&cx=0.5"}]},
       "cameras": [{"name": "near", "eye": [0, 1, 6], "at": [0, 0, 0], "fov": 50}],
       "size": [40, 30]}
    ],
    "cameras": [
      {"name": "front", "eye": [0, 2, 12], "at": [0, 0, 0], "fov": 45},
      {"name": "orbit", "orbit": {"centre": [0, 0, 0], "radius": 11, "height": 3}, "frames": 2,
       "fov": 40}
    ],
    "aovs": "all",
    "size": [48, 32],
    "output": "out/{scene}/{camera}_{frame}.exr",
    "performance": {"threads": 2}
  })");
}

std::string writeJob(const std::string& dir, const json& j, const std::string& name) {
  const std::string path = dir + "/" + name;
  writeFile(path, j.dump(2));
  return path;
}

/// Entry k of a "scenes" job as a one-scene job of its own, writing to sep/<name>/.
json separateJob(const json& many, size_t k) {
  json one = many;
  one.erase("scenes");
  const json& entry = many["scenes"][k];
  for (const auto& item : entry.items())
    if (item.key() != "name") one[item.key()] = item.value();
  one["output"] = "sep/" + entry["name"].get<std::string>() + "/{camera}_{frame}.exr";
  return one;
}

/// Renders `many` as one job and each of its scenes as a separate job, and expects every
/// image to be bit-identical; images of different scenes from one camera must differ (so a
/// scene rendered over the wrong BVH would be caught).
void expectManySceneRunEqualsSeparateRuns(const json& many) {
  const std::string dir = scratchDir();
  std::string out;
  const std::string manyPath = writeJob(dir, many, "many.json");
  ASSERT_EQ(runCommand(apertureBinary() + " batch " + quote(manyPath), &out), 0) << out;
  EXPECT_NE(out.find("scene 2/"), std::string::npos) << "progress names the scene: " << out;
  const app::JobFile file = app::readJobFile(manyPath);
  const size_t sceneCount = many["scenes"].size();
  ASSERT_EQ(file.scenes.size(), sceneCount);
  std::vector<std::string> separate;
  for (size_t k = 0; k < sceneCount; ++k) {
    const std::string path = writeJob(dir, separateJob(many, k), cat("one", k, ".json"));
    ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet " + quote(path), &out), 0) << out;
    separate.push_back(path);
  }
  size_t compared = 0;
  for (size_t k = 0; k < sceneCount; ++k) {
    const app::Job one = app::parseJob(separate[k]);
    const app::Job& inMany = file.scenes[k];
    ASSERT_EQ(one.images.size(), inMany.images.size());
    for (size_t i = 0; i < one.images.size(); ++i) {
      const std::string a = inMany.images[i].output, b = one.images[i].output;
      EXPECT_EQ(test::differingAovs(readExr(a), readExr(b)), "") << a << " vs " << b;
      ++compared;
    }
  }
  EXPECT_EQ(compared, file.imageCount());
  // Scenes 0 and 1 share their cameras, and their meshes differ: so do their images.
  EXPECT_NE(test::differingAovs(readExr(file.scenes[0].images[0].output),
                                readExr(file.scenes[1].images[0].output)),
            "");

  const json summary = readJson(dir + "/out/summary.json");
  EXPECT_EQ(summary["scene_count"], sceneCount);
  EXPECT_EQ(summary["bvh_builds"], sceneCount);
  EXPECT_EQ(summary["images_ok"], file.imageCount());
  ASSERT_EQ(summary["images"].size(), file.imageCount());
  for (size_t k = 0; k < sceneCount; ++k) {
    EXPECT_EQ(summary["scenes"][k]["name"], many["scenes"][k]["name"]);
    EXPECT_EQ(summary["scenes"][k]["images"], file.scenes[k].images.size());
    EXPECT_GT(summary["scenes"][k]["triangles"].get<size_t>(), 0u);
  }
  size_t index = 0;
  for (size_t k = 0; k < sceneCount; ++k)
    for (const app::JobImage& image : file.scenes[k].images) {
      const json& e = summary["images"][index];
      EXPECT_EQ(e["index"], index);
      EXPECT_EQ(e["scene"], many["scenes"][k]["name"]);
      EXPECT_EQ(e["output"], image.output);
      ++index;
    }
}

app::JobFile readScenes(const json& j) { return app::readJobFileText(j.dump(), "job.json", ""); }

/// The message readJobFileText throws for `j` ("" if it parses).
std::string scenesError(const json& j) {
  return test::errorOf([&] { readScenes(j); });
}

void expectError(const json& j, const std::string& expected) {
  const std::string message = scenesError(j);
  EXPECT_NE(message.find(expected), std::string::npos)
      << "expected '" << expected << "' in: " << message;
}

}  // namespace

TEST(BatchScenes, ManySceneBatchRendersTheSameImagesAsSeparateRuns) {
  expectManySceneRunEqualsSeparateRuns(scenesJob());
}

TEST(BatchScenes, ManySceneBatchWithASharedMeshEqualsSeparateRuns) {
  APERTURE_REQUIRE_SHARED_MESH(bunny, "stanford/bun_zipper.ply");
  json many = scenesJob();
  // The bunny (about 0.15 units across) scaled to the spheres' size, between two of them.
  many["scenes"].insert(
      many["scenes"].begin() + 1,
      json{{"name", "bunny"},
           {"scene",
            {{"meshes",
              {{{"path", bunny}, {"transform", {{"scale", 40}, {"translate", {1, -4, 0}}}}}}}}}});
  expectManySceneRunEqualsSeparateRuns(many);
}

TEST(BatchScenes, ShardsAndResumeWorkOverTheFlattenedImageList) {
  const std::string dir = scratchDir();
  const std::string path = writeJob(dir, scenesJob(), "many.json");
  const app::JobFile file = app::readJobFile(path);
  ASSERT_EQ(file.imageCount(), 7u);  // 3 + 3 + 1
  std::string out;
  for (const char* shard : {"0/2", "1/2"})
    ASSERT_EQ(
        runCommand(apertureBinary() + " batch --quiet --shard " + shard + " " + quote(path), &out),
        0)
        << out;
  const json s0 = readJson(dir + "/out/summary.shard-0-of-2.json");
  const json s1 = readJson(dir + "/out/summary.shard-1-of-2.json");
  // Indices run over all scenes: shard 0 has 0 2 4 6, shard 1 has 1 3 5.
  ASSERT_EQ(s0["images"].size(), 4u);
  ASSERT_EQ(s1["images"].size(), 3u);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(s0["images"][i]["index"], 2 * i);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(s1["images"][i]["index"], 2 * i + 1);
  EXPECT_EQ(s1["images"][1]["scene"], "large");  // index 3: the first image of scene 1
  for (const app::Job& scene : file.scenes)
    for (const app::JobImage& image : scene.images)
      EXPECT_TRUE(test::fileExists(image.output)) << image.output;
  // Everything is up to date: --resume skips every image and loads no scene.
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet --resume " + quote(path), &out), 0)
      << out;
  const json resumed = readJson(dir + "/out/summary.json");
  EXPECT_EQ(resumed["images_skipped"], 7);
  EXPECT_EQ(resumed["bvh_builds"], 0);
  // One output gone: only its scene is loaded again.
  fs::remove(file.scenes[1].images[2].output);
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet --resume " + quote(path), &out), 0)
      << out;
  const json again = readJson(dir + "/out/summary.json");
  EXPECT_EQ(again["images_ok"], 1);
  EXPECT_EQ(again["bvh_builds"], 1);
  EXPECT_EQ(again["scenes"][1]["bvh_builds"], 1);
  EXPECT_EQ(again["scenes"][0]["bvh_builds"], 0);
}

TEST(BatchScenesJob, EntriesMergeOverTheSharedKeys) {
  const app::JobFile file = readScenes(scenesJob());
  ASSERT_TRUE(file.multiScene);
  ASSERT_EQ(file.scenes.size(), 3u);
  EXPECT_EQ(file.scenes[0].images.size(), 3u);
  EXPECT_EQ(file.scenes[2].images.size(), 1u);
  EXPECT_EQ(file.scenes[0].images[0].params.width, 48);
  EXPECT_EQ(file.scenes[2].images[0].params.width, 40);  // the entry's own size
  EXPECT_EQ(file.scenes[2].images[0].camera, "near");
  EXPECT_EQ(file.scenes[1].meshes[0].spec, "procedural:spheres?tris=20000");
  EXPECT_EQ(file.scenes[1].images[0].output, "out/large/front_0.exr");
  EXPECT_EQ(file.scenes[1].images[0].index, 3u);
  EXPECT_EQ(file.scenes[1].images[0].scene, 1u);
  EXPECT_EQ(file.scenes[1].sceneName, "large");
  EXPECT_EQ(file.outputDirectory, "out/");
  // A job without "scenes" is one scene; parseJobText refuses one with "scenes".
  json one = scenesJob();
  one.erase("scenes");
  one["scene"] = {{"meshes", {{{"path", "procedural:sphere"}}}}};
  one["output"] = "out/{camera}_{frame}.exr";
  EXPECT_FALSE(readScenes(one).multiScene);
  EXPECT_EQ(readScenes(one).scenes.size(), 1u);
  EXPECT_NE(test::errorOf([] {
              app::parseJobText(scenesJob().dump(), "job.json", "");
            }).find("readJobFile"),
            std::string::npos);
}

TEST(BatchScenesJob, ErrorsNameTheJsonPath) {
  json j = scenesJob();
  j["output"] = "out/{camera}_{frame}.exr";
  expectError(j, "job.json: output: 'out/{camera}_{frame}.exr' has no {scene}: in a job of 3");
  j = scenesJob();
  j["scenes"][1]["output"] = "mine/{camera}_{frame}.exr";
  expectError(j, "job.json: scenes[1].output: 'mine/{camera}_{frame}.exr' has no {scene}");
  j = scenesJob();
  j["preview"] = "prev/{camera}_{frame}.png";
  expectError(j, "job.json: preview: 'prev/{camera}_{frame}.png' has no {scene}");
  j = scenesJob();
  j["scenes"][2]["cameras"][0]["eye"] = {0, 1};
  expectError(j, "job.json: scenes[2].cameras[0].eye: expected an array of 3 numbers");
  j = scenesJob();
  j["cameras"][1]["frames"] = 0;  // a shared key: named where it was written
  expectError(j, "job.json: cameras[1].frames: 0: must be in");
  j = scenesJob();
  j["aovs"] = "depht";
  expectError(j, "job.json: aovs: ");
  j = scenesJob();
  j["scenes"][0]["camerass"] = json::array();
  expectError(j, "job.json: scenes[0].camerass: unknown key (did you mean 'cameras'?)");
  j = scenesJob();
  j["scenesx"] = 1;
  expectError(j, "job.json: scenesx: unknown key (did you mean 'scenes'?)");
  j = scenesJob();
  j["scenes"][1]["scene"]["meshes"][0]["path"] = "nothere.ply";
  expectError(j, "job.json: scenes[1].scene.meshes[0].path: 'nothere.ply': no such file");
  j = scenesJob();
  j["scenes"][1]["name"] = "small";
  expectError(j, "job.json: scenes[1].name: 'small': a scene of that name already exists");
  j = scenesJob();
  j["scenes"][0].erase("name");
  expectError(j, "job.json: scenes[0].name: required key is missing");
  j = scenesJob();
  j["scenes"][0]["name"] = "../up";
  expectError(j, "job.json: scenes[0].name: '../up': a scene name is");
  j = scenesJob();
  j["scenes"][2].erase("scene");
  expectError(j, "job.json: scenes[2].scene: required key is missing");
  j = scenesJob();
  j["scene"] = j["scenes"][0]["scene"];
  expectError(j, "job.json: scene: a job with \"scenes\" gives each scene in its entry");
  j = scenesJob();
  j["scenes"] = json::array();
  expectError(j, "job.json: scenes: needs at least one scene");
  j = scenesJob();
  j["scenes"][1]["performance"] = {{"threads", 1}};
  expectError(j, "job.json: scenes[1].performance.threads: 1: every scene must use the same");
  // {scene} belongs to jobs with "scenes"; one scene of "scenes" may do without it.
  json one = scenesJob();
  one.erase("scenes");
  one["scene"] = {{"meshes", {{{"path", "procedural:sphere"}}}}};
  expectError(one, "unknown placeholder '{scene}'");
  j = scenesJob();
  j["scenes"].erase(1);
  j["scenes"].erase(1);
  j["output"] = "out/{camera}_{frame}.exr";
  EXPECT_EQ(scenesError(j), "");
}

TEST(BatchScenes, MaxMemoryBudgetsTheLargestTwoConsecutiveScenes) {
  const std::string dir = scratchDir();
  const std::vector<std::string> meshes = {
      "procedural:spheres?tris=1000", "procedural:spheres?tris=300000",
      "procedural:spheres?tris=200000", "procedural:spheres?tris=1000"};
  json j = scenesJob();
  j["scenes"] = json::array();
  for (size_t k = 0; k < meshes.size(); ++k)
    j["scenes"].push_back(
        {{"name", cat("s", k)}, {"scene", {{"meshes", {{{"path", meshes[k]}}}}}}});
  j["aovs"] = "depth";
  const std::string path = writeJob(dir, j, "many.json");
  // The estimate of scenes 1 and 2 alive together, computed here from apps/services/limits.h: every
  // mesh of both, the largest image's two framebuffers.
  const uint64_t pixels = 48 * 32;
  const MemoryEstimate pair = estimateMemory({meshes[1], meshes[2]}, pixels, 1, AovSet{},
                                             framebufferBytesPerPixel(parseAovSet("depth")) * 2);
  const MemoryEstimate largestAlone = estimateMemory(
      {meshes[1]}, pixels, 1, AovSet{}, framebufferBytesPerPixel(parseAovSet("depth")) * 2);
  ASSERT_LT(largestAlone.total() + (1u << 20), pair.total());
  std::string out;
  // Enough for any one scene, not for two consecutive ones: refused, naming the pair.
  const std::string tooSmall = std::to_string(largestAlone.total() + (1u << 20));
  EXPECT_EQ(
      runCommand(apertureBinary() + " batch --dry-run --max-memory " + tooSmall + " " + quote(path),
                 &out),
      1)
      << out;
  EXPECT_NE(out.find("scenes 's1' and 's2', alive together"), std::string::npos) << out;
  const std::string enough = std::to_string(pair.total() + 4096);
  EXPECT_EQ(
      runCommand(apertureBinary() + " batch --dry-run --max-memory " + enough + " " + quote(path),
                 &out),
      0)
      << out;
}

namespace {

/// What the pipeline test records: events in order, scenes alive now and at most.
struct PipelineLog {
  std::mutex mutex;
  std::condition_variable loadedCv;
  std::vector<std::string> events;
  size_t loaded = 0;  ///< scenes whose load returned
  int alive = 0, peak = 0;
};

/// A scene of the pipeline test: counted while alive, its release logged.
struct TrackedScene {
  TrackedScene(size_t index, PipelineLog& log) : k(index), record(log) {
    std::lock_guard<std::mutex> lock(record.mutex);
    record.peak = std::max(record.peak, ++record.alive);
  }
  ~TrackedScene() {
    std::lock_guard<std::mutex> lock(record.mutex);
    --record.alive;
    record.events.push_back(cat("free ", k));
  }
  size_t k;
  PipelineLog& record;
};

size_t positionOf(const std::vector<std::string>& log, const std::string& event) {
  return size_t(std::find(log.begin(), log.end(), event) - log.begin());
}

}  // namespace

TEST(ScenePipeline, NextSceneLoadsWhileOneRendersAndAtMostTwoAreAlive) {
  constexpr size_t kScenes = 5;
  PipelineLog r;
  using Scene = std::unique_ptr<TrackedScene>;
  const std::function<Scene(size_t)> load = [&](size_t k) {
    {
      std::lock_guard<std::mutex> lock(r.mutex);
      r.events.push_back(cat("load ", k));
    }
    Scene s = std::make_unique<TrackedScene>(k, r);
    std::lock_guard<std::mutex> lock(r.mutex);
    r.loaded = std::max(r.loaded, k + 1);
    r.loadedCv.notify_all();
    return s;
  };
  const std::function<void(size_t, Scene&)> render = [&](size_t k, Scene& s) {
    ASSERT_EQ(s->k, k);
    std::unique_lock<std::mutex> lock(r.mutex);
    r.events.push_back(cat("render ", k));
    // Scene k's last image does not finish until scene k+1 is built: a pipeline that loads
    // the next scene only after rendering would never get there. (The timeout only turns such
    // a deadlock into a failure; nothing is timed.)
    if (k + 1 < kScenes) {
      EXPECT_TRUE(
          r.loadedCv.wait_for(lock, std::chrono::seconds(60), [&] { return r.loaded > k + 1; }))
          << "scene " << k + 1 << " was not loaded while scene " << k << " rendered";
    }
    r.events.push_back(cat("rendered ", k));
  };
  app::pipelineScenes(kScenes, load, render);
  const std::vector<std::string>& log = r.events;
  EXPECT_EQ(r.alive, 0);
  EXPECT_EQ(r.peak, 2);
  for (size_t k = 0; k < kScenes; ++k) {
    EXPECT_LT(positionOf(log, cat("load ", k)), positionOf(log, cat("render ", k)));
    EXPECT_LT(positionOf(log, cat("rendered ", k)), positionOf(log, cat("free ", k)));
    if (k + 1 < kScenes) {  // k+1 is built before k's render ends
      EXPECT_LT(positionOf(log, cat("load ", k + 1)), positionOf(log, cat("rendered ", k)));
    }
    if (k + 2 < kScenes) {  // k is released before k+2 starts loading
      EXPECT_LT(positionOf(log, cat("free ", k)), positionOf(log, cat("load ", k + 2)));
    }
  }
}

TEST(ScenePipeline, LoadErrorsPropagateAfterTheLoadInFlight) {
  const std::function<int(size_t)> load = [](size_t k) -> int {
    if (k == 2) throw Error("scene 2 is broken");
    return int(k);
  };
  std::vector<size_t> rendered;
  const std::function<void(size_t, int&)> render = [&](size_t k, int&) { rendered.push_back(k); };
  EXPECT_EQ(test::errorOf([&] { app::pipelineScenes(4, load, render); }), "scene 2 is broken");
  EXPECT_EQ(rendered, (std::vector<size_t>{0, 1}));
}
