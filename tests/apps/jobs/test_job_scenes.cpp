// Job files of several scenes ("scenes", apps/jobs/job.h, docs/batch.md): each entry merged over
// the shared keys, {scene} in the patterns, and errors naming the JSON path.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "apps/jobs/job.h"
#include "core/util/error.h"
#include "tests/job_support.h"
#include "tests/support.h"

using namespace aperture;
using aperture::test::scenesJob;
using nlohmann::json;

namespace {

app::JobFile readScenes(const json& j) { return app::readJobFileText(j.dump(), "job.json", ""); }

/// The message readJobFileText throws for `j` ("" if it parses).
std::string scenesError(const json& j) {
  return test::errorOf([&] { readScenes(j); });
}

void expectScenesError(const json& j, const std::string& expected) {
  const std::string message = scenesError(j);
  EXPECT_NE(message.find(expected), std::string::npos)
      << "expected '" << expected << "' in: " << message;
}

}  // namespace

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
  expectScenesError(j,
                    "job.json: output: 'out/{camera}_{frame}.exr' has no {scene}: in a job of 3");
  j = scenesJob();
  j["scenes"][1]["output"] = "mine/{camera}_{frame}.exr";
  expectScenesError(j, "job.json: scenes[1].output: 'mine/{camera}_{frame}.exr' has no {scene}");
  j = scenesJob();
  j["preview"] = "prev/{camera}_{frame}.png";
  expectScenesError(j, "job.json: preview: 'prev/{camera}_{frame}.png' has no {scene}");
  j = scenesJob();
  j["scenes"][2]["cameras"][0]["eye"] = {0, 1};
  expectScenesError(j, "job.json: scenes[2].cameras[0].eye: expected an array of 3 numbers");
  j = scenesJob();
  j["cameras"][1]["frames"] = 0;  // a shared key: named where it was written
  expectScenesError(j, "job.json: cameras[1].frames: 0: must be in");
  j = scenesJob();
  j["aovs"] = "depht";
  expectScenesError(j, "job.json: aovs: ");
  j = scenesJob();
  j["scenes"][0]["camerass"] = json::array();
  expectScenesError(j, "job.json: scenes[0].camerass: unknown key (did you mean 'cameras'?)");
  j = scenesJob();
  j["scenesx"] = 1;
  expectScenesError(j, "job.json: scenesx: unknown key (did you mean 'scenes'?)");
  j = scenesJob();
  j["scenes"][1]["scene"]["meshes"][0]["path"] = "nothere.ply";
  expectScenesError(j, "job.json: scenes[1].scene.meshes[0].path: 'nothere.ply': no such file");
  j = scenesJob();
  j["scenes"][1]["name"] = "small";
  expectScenesError(j, "job.json: scenes[1].name: 'small': a scene of that name already exists");
  j = scenesJob();
  j["scenes"][0].erase("name");
  expectScenesError(j, "job.json: scenes[0].name: required key is missing");
  j = scenesJob();
  j["scenes"][0]["name"] = "../up";
  expectScenesError(j, "job.json: scenes[0].name: '../up': a scene name is");
  j = scenesJob();
  j["scenes"][2].erase("scene");
  expectScenesError(j, "job.json: scenes[2].scene: required key is missing");
  j = scenesJob();
  j["scene"] = j["scenes"][0]["scene"];
  expectScenesError(j, "job.json: scene: a job with \"scenes\" gives each scene in its entry");
  j = scenesJob();
  j["scenes"] = json::array();
  expectScenesError(j, "job.json: scenes: needs at least one scene");
  j = scenesJob();
  j["scenes"][1]["performance"] = {{"threads", 1}};
  expectScenesError(j, "job.json: scenes[1].performance.threads: 1: every scene must use the same");
  // {scene} belongs to jobs with "scenes"; one scene of "scenes" may do without it.
  json one = scenesJob();
  one.erase("scenes");
  one["scene"] = {{"meshes", {{{"path", "procedural:sphere"}}}}};
  expectScenesError(one, "unknown placeholder '{scene}'");
  j = scenesJob();
  j["scenes"].erase(1);
  j["scenes"].erase(1);
  j["output"] = "out/{camera}_{frame}.exr";
  EXPECT_EQ(scenesError(j), "");
}
