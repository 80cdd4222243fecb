// Shards of a batch (apps/batch/shard.h): K/N, a Slurm array task and a Kubernetes indexed Job
// give K and N or an error naming the variables, and the shards of a job render every image
// exactly once.
#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "apps/batch/shard.h"
#include "core/util/error.h"
#include "tests/job_support.h"
#include "tests/support.h"

using namespace aperture;
using aperture::app::Job;
using aperture::test::apertureBinary;
using aperture::test::imagesWithStatus;
using aperture::test::orbitJob;
using aperture::test::quote;
using aperture::test::readJson;
using aperture::test::runCommand;
using aperture::test::runShards;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using nlohmann::json;
namespace fs = std::filesystem;

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
  EXPECT_EQ(imagesWithStatus(shard1, "ok"), (std::set<size_t>{1, 4, 7, 10}));
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
