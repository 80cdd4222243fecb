// `aperture batch --merge-summaries` (apps/batch/merge_summaries.h): the shards' summaries merged
// into one that names the images no shard rendered, and summaries of different jobs refused.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/jobs/job.h"
#include "tests/job_support.h"
#include "tests/support.h"

using namespace aperture;
using aperture::app::Job;
using aperture::test::apertureBinary;
using aperture::test::baseJob;
using aperture::test::orbitJob;
using aperture::test::quote;
using aperture::test::readJson;
using aperture::test::runBatch;
using aperture::test::runCommand;
using aperture::test::runShards;
using aperture::test::scratchDir;
using aperture::test::writeFile;
using aperture::test::writeJob;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

/// "camera frame N" of every image of the job whose index is k modulo n.
std::vector<std::string> labelsOfShard(const Job& job, size_t k, size_t n) {
  std::vector<std::string> labels;
  for (const app::JobImage& image : job.images)
    if (image.index % n == k)
      labels.push_back(image.camera + " frame " + std::to_string(image.frame));
  return labels;
}

}  // namespace

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
  ASSERT_EQ(runBatch("--quiet", writeJob(dir + "/a", a), &out), 0) << out;
  ASSERT_EQ(runBatch("--quiet", writeJob(dir + "/b", b), &out), 0) << out;
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
