// Dataset outputs from the command line and job files: `render --out x.png|.npy|...` with one
// AOV, "outputs" in jobs (several AOVs in several formats per image), refusals before
// rendering, and --resume over every file of an image. Values are checked against the EXR of
// the same camera, read by the EXR reader, through the documented formulas.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "apps/jobs/job.h"
#include "core/exr/exr.h"
#include "core/io/dataset_image.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::apertureBinary;
using test::runCommand;
using test::scratchDir;

const std::string kCamera =
    "--mesh procedural:sphere --eye 0,0,4 --at 0,0,0 --fov 40 --size 40,30 --quiet";

std::vector<uint16_t> readPng16(const std::string& path) {
  const test::DecodedImage<uint16_t> png = test::readImageFile<uint16_t>(path);
  EXPECT_EQ(png.info.type, SampleType::UInt16) << path;
  EXPECT_EQ(png.info.channels, 1) << path;
  return png.samples;
}

/// The 16-bit PNG rule applied to an EXR's Z: round(Z · scale) in [1, 65535], else 0.
std::vector<uint16_t> png16FromZ(const std::vector<float>& z, double scale) {
  std::vector<uint16_t> v;
  for (float d : z) {
    const double r = std::isfinite(d) ? std::round(double(d) * scale) : 0.0;
    v.push_back(r >= 1 && r <= 65535 ? uint16_t(r) : 0);
  }
  return v;
}

/// Counts the misses (+inf) and hits of a depth image; the test scenes need both.
void expectHitsAndMisses(const std::vector<float>& z) {
  size_t misses = 0;
  for (float d : z) misses += std::isinf(d);
  EXPECT_GT(misses, 0u);
  EXPECT_LT(misses, z.size());
}

TEST(DatasetCli, RenderPngDepthIsTheExrZThroughTheFormula) {
  const std::string dir = scratchDir();
  ASSERT_EQ(
      runCommand(apertureBinary() + " render " + kCamera + " --aov depth --out " + dir + "/d.exr"),
      0);
  ASSERT_EQ(runCommand(apertureBinary() + " render " + kCamera +
                       " --aov depth --depth-scale 5000 --out " + dir + "/d.png"),
            0);
  const Framebuffer exr = readExr(dir + "/d.exr");
  expectHitsAndMisses(exr.depth);
  EXPECT_EQ(readPng16(dir + "/d.png"), png16FromZ(exr.depth, 5000));
  EXPECT_FALSE(fs::exists(dir + "/d.exr.png"));
}

TEST(DatasetCli, RenderNpyAndPfmAreTheExrBitForBit) {
  const std::string dir = scratchDir();
  ASSERT_EQ(
      runCommand(apertureBinary() + " render " + kCamera + " --aov normal --out " + dir + "/n.exr"),
      0);
  for (const char* name : {"/n.npy", "/n.pfm"}) {
    ASSERT_EQ(
        runCommand(apertureBinary() + " render " + kCamera + " --aov normal --out " + dir + name),
        0);
    const DatasetImage back = readDatasetImage(dir + name);
    const Framebuffer exr = readExr(dir + "/n.exr");
    EXPECT_EQ(back.channels, 3);
    ASSERT_EQ(back.f32.size(), exr.normal.size());
    EXPECT_EQ(std::memcmp(back.f32.data(), exr.normal.data(), 4 * exr.normal.size()), 0) << name;
  }
}

TEST(DatasetCli, UnsupportedPairsAreRefusedBeforeRendering) {
  const std::string dir = scratchDir();
  std::string out;
  EXPECT_EQ(
      runCommand(apertureBinary() + " render " + kCamera + " --aov normal --out " + dir + "/n.png",
                 &out),
      1);
  EXPECT_NE(out.find("'normal'"), std::string::npos) << out;
  EXPECT_NE(out.find("16-bit PNG"), std::string::npos) << out;
  EXPECT_EQ(out.find("rendered"), std::string::npos) << out;

  EXPECT_EQ(runCommand(apertureBinary() + " render " + kCamera + " --aov depth,normal --out " +
                           dir + "/x.npy",
                       &out),
            1);
  EXPECT_NE(out.find("depth,normal"), std::string::npos) << out;
  EXPECT_NE(out.find("outputs"), std::string::npos) << out;

  EXPECT_EQ(
      runCommand(apertureBinary() + " render " + kCamera + " --aov primid --out " + dir + "/p.pfm",
                 &out),
      1);
  EXPECT_NE(out.find("PFM"), std::string::npos) << out;

  EXPECT_EQ(runCommand(apertureBinary() + " render " + kCamera +
                           " --aov depth --depth-scale -1 --out " + dir + "/d.png",
                       &out),
            1);
  EXPECT_NE(out.find("--depth-scale"), std::string::npos) << out;
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(DatasetCli, OutOfRangeDepthsAreWarnedAbout) {
  const std::string dir = scratchDir();
  std::string out;
  // At 100000 units per scene unit every depth (about 3 to 4) exceeds 65535.
  ASSERT_EQ(runCommand(apertureBinary() + " render " + kCamera +
                           " --aov depth --depth-scale 100000 --out " + dir + "/d.png",
                       &out),
            0);
  EXPECT_NE(out.find("warning: " + dir + "/d.png"), std::string::npos) << out;
  for (uint16_t v : readPng16(dir + "/d.png")) EXPECT_EQ(v, 0);
}

json multiOutputJob(const std::string& dir) {
  json job = json::parse(R"({
    "scene": {"meshes": [{"path": "procedural:sphere"}]},
    "cameras": [{"name": "a", "eye": [0, 0, 4], "at": [0, 0, 0], "fov": 40},
                {"name": "b", "eye": [1, 0, 4], "at": [0, 0, 0], "fov": 40}],
    "size": [40, 30],
    "aovs": "depth,normal,primid",
    "depth_scale": 2000
  })");
  job["outputs"] = json::array({{{"aov", "depth"}, {"path", dir + "/depth/{camera}.png"}},
                                {{"aov", "normal"}, {"path", dir + "/normal/{camera}.npy"}},
                                {{"aov", "primid"}, {"path", dir + "/id/{camera}.tif"}},
                                {{"aov", "all"}, {"path", dir + "/exr/{camera}.exr"}}});
  return job;
}

TEST(DatasetJob, SeveralOutputsInSeveralFormatsAndResume) {
  const std::string dir = scratchDir();
  test::writeFile(dir + "/job.json", multiOutputJob(dir).dump());
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet " + dir + "/job.json", &out), 0) << out;
  for (const char* camera : {"a", "b"}) {
    const Framebuffer exr = readExr(dir + "/exr/" + camera + ".exr");
    expectHitsAndMisses(exr.depth);
    EXPECT_EQ(readPng16(dir + "/depth/" + camera + ".png"), png16FromZ(exr.depth, 2000));
    const DatasetImage normal = readDatasetImage(dir + "/normal/" + camera + ".npy");
    ASSERT_EQ(normal.f32.size(), exr.normal.size());
    EXPECT_EQ(std::memcmp(normal.f32.data(), exr.normal.data(), 4 * exr.normal.size()), 0);
    const test::DecodedImage<uint32_t> ids =
        test::readImageFile<uint32_t>(dir + "/id/" + camera + ".tif");
    EXPECT_EQ(ids.info.type, SampleType::UInt32);
    EXPECT_EQ(ids.samples, exr.primId);
  }
  // The summary lists every file of an image in writing order, the EXR last.
  const json summary = json::parse(test::readFile(dir + "/exr/summary.json"));
  EXPECT_EQ(summary["images"][0]["files"], json::array({dir + "/depth/a.png", dir + "/normal/a.npy",
                                                        dir + "/id/a.tif", dir + "/exr/a.exr"}));

  ASSERT_EQ(runCommand(apertureBinary() + " batch --resume " + dir + "/job.json", &out), 0);
  EXPECT_NE(out.find("2 of 2 images up to date"), std::string::npos) << out;
  fs::remove(dir + "/normal/b.npy");
  ASSERT_EQ(runCommand(apertureBinary() + " batch --resume " + dir + "/job.json", &out), 0);
  EXPECT_NE(out.find("1 of 2 images up to date, 1 stale"), std::string::npos) << out;
  EXPECT_NE(out.find("normal file " + dir + "/normal/b.npy is missing"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(dir + "/normal/b.npy"));
}

TEST(DatasetJob, DatasetOnlyJobResumesOnItsFiles) {
  const std::string dir = scratchDir();
  json job = multiOutputJob(dir);
  job["outputs"].erase(3);  // no EXR
  test::writeFile(dir + "/job.json", job.dump());
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet " + dir + "/job.json", &out), 0) << out;
  EXPECT_TRUE(fs::exists(dir + "/depth/summary.json"));
  EXPECT_FALSE(fs::exists(dir + "/exr"));
  ASSERT_EQ(runCommand(apertureBinary() + " batch --resume " + dir + "/job.json", &out), 0);
  EXPECT_NE(out.find("2 of 2 images up to date"), std::string::npos) << out;
  fs::remove(dir + "/id/a.tif");
  ASSERT_EQ(runCommand(apertureBinary() + " batch --resume " + dir + "/job.json", &out), 0);
  EXPECT_NE(out.find("1 of 2 images up to date"), std::string::npos) << out;
}

/// The message parseJobText throws for `j` ("" if it parses).
std::string jobError(const json& j) {
  try {
    app::parseJobText(j.dump(), "job.json", "");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(DatasetJob, BadOutputsAreRefusedAtParse) {
  const std::string dir = scratchDir();
  EXPECT_EQ(jobError(multiOutputJob(dir)), "");

  json notRendered = multiOutputJob(dir);
  notRendered["outputs"][0]["aov"] = "distance";
  EXPECT_NE(jobError(notRendered).find("not among the job's \"aovs\""), std::string::npos)
      << jobError(notRendered);

  json normalPng = multiOutputJob(dir);
  normalPng["outputs"][1]["path"] = dir + "/normal/{camera}.png";
  EXPECT_NE(jobError(normalPng).find("16-bit PNG"), std::string::npos) << jobError(normalPng);

  json samePath = multiOutputJob(dir);
  samePath["outputs"][1]["path"] = dir + "/depth/{camera}.npy";
  samePath["outputs"][2]["path"] = dir + "/depth/{camera}.npy";
  EXPECT_NE(jobError(samePath).find("both write"), std::string::npos) << jobError(samePath);

  json twoExr = multiOutputJob(dir);
  twoExr["output"] = dir + "/x/{camera}.exr";
  EXPECT_NE(jobError(twoExr).find("already writes an EXR"), std::string::npos) << jobError(twoExr);

  json badScale = multiOutputJob(dir);
  badScale["depth_scale"] = 0;
  EXPECT_NE(jobError(badScale).find("depth_scale"), std::string::npos) << jobError(badScale);

  json twoAovs = multiOutputJob(dir);
  twoAovs["outputs"][1]["aov"] = "depth,normal";
  EXPECT_NE(jobError(twoAovs).find("holds one AOV"), std::string::npos) << jobError(twoAovs);
}

}  // namespace
}  // namespace aperture
