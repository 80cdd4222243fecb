// A job file's "lidars" (apps/jobs/job_lidar.h): read and checked with the job (errors name the
// file and the key path, nothing is written), and scanned by `aperture batch` through the
// job's scene beside its images: the cloud equals `aperture scan`'s of the same sensor.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "apps/jobs/job.h"
#include "core/engine/layers.h"
#include "tests/job_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

nlohmann::json jobWithLidar() {
  nlohmann::json j = test::baseJob();
  j["lidars"] = nlohmann::json::parse(R"([
    {"lidar": "VLP-16", "output": "scans/{sweep:03d}.ply", "sweeps": 2, "frame": "world",
     "returns": "strongest", "surfaces": 3, "noise": {"sigma": 0.01, "seed": 5}}
  ])");
  return j;
}

TEST(JobLidar, EntriesAreReadAsTheScanFlags) {
  const std::string dir = test::scratchDir();
  std::filesystem::create_directories(dir + "/scans");
  const app::Job job = test::parseJobJson(jobWithLidar(), dir);
  ASSERT_EQ(job.lidars.size(), 1u);
  const app::ScanRequest& r = job.lidars[0].request;
  EXPECT_EQ(r.lidar, "VLP-16");
  EXPECT_EQ(r.sweeps, 2);
  EXPECT_EQ(r.options.frame, app::ScanFrame::World);
  EXPECT_EQ(r.options.returns, app::ScanReturns::Strongest);
  EXPECT_EQ(r.options.maxSurfaces, 3);
  EXPECT_EQ(r.options.noise.sigma, 0.01);
  EXPECT_EQ(r.options.noise.seed, 5u);
  EXPECT_EQ(job.lidars[0].prepared.paths,
            (std::vector<std::string>{dir + "/scans/000.ply", dir + "/scans/001.ply"}));
  EXPECT_EQ(job.lidars[0].prepared.sensor.beams.size(), 16u);
}

TEST(JobLidar, TheJobsSceneHoldsWhatTheScansNeed) {
  const std::string dir = test::scratchDir();
  std::filesystem::create_directories(dir + "/scans");
  nlohmann::json j = jobWithLidar();
  j["lidars"][0]["properties"] = nlohmann::json::array({"semantic"});
  const app::Job job = test::parseJobJson(j, dir);
  const app::SceneSpec spec = job.sceneSpec();
  // The same as `aperture scan` asks for (withScanNeeds): the properties carried and, for
  // strongest returns, the context filter of the layers' search.
  const PropertyAov semantic{PropertyDomain::Face, "semantic"};
  EXPECT_NE(std::find(spec.properties.begin(), spec.properties.end(), semantic),
            spec.properties.end());
  EXPECT_EQ(spec.build.contextFilter, app::scanNeedsContextFilter(job.lidars[0].request.options));
  EXPECT_TRUE(app::scanNeedsContextFilter(job.lidars[0].request.options) ||
              defaultLayerMethod() != LayerMethod::Filter);
  j["lidars"][0]["returns"] = "first";
  EXPECT_FALSE(test::parseJobJson(j, dir).sceneSpec().build.contextFilter);
}

TEST(JobLidar, BadEntriesNameTheKeyPath) {
  const std::string dir = test::scratchDir();
  std::filesystem::create_directories(dir + "/scans");
  nlohmann::json j = jobWithLidar();
  j["lidars"][0]["frame"] = "wrld";
  std::string e = test::jobParseError(j, dir);
  EXPECT_NE(e.find("job.json: lidars[0].frame"), std::string::npos) << e;
  EXPECT_NE(e.find("world"), std::string::npos) << e;
  j = jobWithLidar();
  j["lidars"][0]["lidar"] = "VLP-61";
  e = test::jobParseError(j, dir);
  EXPECT_NE(e.find("lidars[0]"), std::string::npos) << e;
  EXPECT_NE(e.find("VLP-16"), std::string::npos) << e;
  j = jobWithLidar();
  j["lidars"][0]["sweeeps"] = 2;
  e = test::jobParseError(j, dir);
  EXPECT_NE(e.find("sweeeps"), std::string::npos) << e;
  j = jobWithLidar();
  j["lidars"][0]["output"] = "scans/one.ply";
  e = test::jobParseError(j, dir);
  EXPECT_NE(e.find("{sweep}"), std::string::npos) << e;
  j = jobWithLidar();
  j["lidars"][0].erase("output");
  e = test::jobParseError(j, dir);
  EXPECT_NE(e.find("lidars[0].output"), std::string::npos) << e;
}

TEST(JobLidar, BatchScansTheJobsSceneAsScanDoes) {
  const std::string dir = test::scratchDir();
  std::filesystem::create_directories(dir + "/scans");
  nlohmann::json j = test::baseJob();
  j["lidars"] = nlohmann::json::parse(
      R"([{"lidar": "VLP-16", "output": "scans/batch.ply", "frame": "world"}])");
  j["lidars"][0]["trajectory"] = "pose.txt";
  test::writeFile(dir + "/pose.txt", "0 3 0 0 0 0 0 1\n");
  const std::string path = test::writeJob(dir, j);
  std::string out;
  ASSERT_EQ(test::runBatch("--quiet", path, &out), 0) << out;
  ASSERT_TRUE(test::fileExists(dir + "/scans/batch.ply")) << out;
  ASSERT_EQ(test::runCommand(test::apertureBinary() +
                                 " scan --quiet --mesh procedural:sphere --lidar VLP-16 --frame "
                                 "world --trajectory " +
                                 test::quote(dir + "/pose.txt") + " --out " +
                                 test::quote(dir + "/scans/scan.ply"),
                             &out),
            0)
      << out;
  const std::string a = test::readFile(dir + "/scans/batch.ply");
  const std::string b = test::readFile(dir + "/scans/scan.ply");
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace aperture
