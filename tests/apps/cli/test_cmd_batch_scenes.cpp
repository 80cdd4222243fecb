// `aperture batch` of several scenes end to end (apps/cli/cmd_batch.cpp, docs/batch.md): the
// images of a many-scene job are those of K separate one-scene runs, bit for bit, also with
// --shard and --resume, and --max-memory budgets the largest two consecutive scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/jobs/job.h"
#include "apps/services/limits.h"
#include "core/exr/exr.h"
#include "core/util/error.h"
#include "tests/job_support.h"
#include "tests/support.h"

using namespace aperture;
using aperture::test::apertureBinary;
using aperture::test::quote;
using aperture::test::readJson;
using aperture::test::runCommand;
using aperture::test::scenesJob;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using aperture::test::writeJob;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

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
