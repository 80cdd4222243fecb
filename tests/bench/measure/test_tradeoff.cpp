// The speed/accuracy study (`aperture tradeoff`), --preset, and `bench --sweep aovs`, run
// through the executable.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/exr/exr.h"
#include "tests/support.h"

using namespace aperture;
using aperture::test::apertureBinary;
using aperture::test::runCommand;
using aperture::test::scratchDir;

namespace {

/// Rows of a CSV with a header line, as column name -> text (no quoted commas in the columns
/// read here: knob, value is quoted and read as the remainder).
std::vector<std::map<std::string, std::string>> readCsv(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::stringstream h(line);
  for (std::string n; std::getline(h, n, ',');) names.push_back(n);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    for (char c : line) {
      if (c == '"')
        quoted = !quoted;
      else if (c == ',' && !quoted)
        cells.push_back(cell), cell.clear();
      else
        cell += c;
    }
    cells.push_back(cell);
    std::map<std::string, std::string> row;
    for (size_t k = 0; k < names.size() && k < cells.size(); ++k) row[names[k]] = cells[k];
    rows.push_back(row);
  }
  return rows;
}

const char* kThinLensCity =
    " --mesh procedural:city --camera thinlens --aperture 0.4 --focus 8 --eye 0,4,14 "
    "--at 0,2,0 --fov 50 --size 96,64";

}  // namespace

TEST(Tradeoff, QuickStudyCoversEveryKnobAndSamplesReduceTheError) {
  const std::string dir = scratchDir();
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " tradeoff --quiet --quick --reference-spp 64" +
                           kThinLensCity + " --out-dir " + dir + " --name t",
                       &out),
            0)
      << out;
  const auto rows = readCsv(dir + "/t.csv");
  std::set<std::string> knobs;
  std::map<std::string, double> sppRmse;
  int pareto = 0;
  for (const auto& r : rows) {
    knobs.insert(r.at("knob"));
    pareto += r.at("pareto") == "1";
    if (r.at("knob") == "base") sppRmse["1"] = std::stod(r.at("rmse"));
    if (r.at("knob") == "spp") sppRmse[r.at("spp")] = std::stod(r.at("rmse"));
    EXPECT_GT(std::stod(r.at("frame_s")), 0.0);
  }
  for (const char* k :
       {"base", "bvh", "packet", "spp", "placement", "exr_color", "exr_compression", "tile"})
    EXPECT_TRUE(knobs.count(k)) << "knob " << k << " missing from the study";
  EXPECT_GT(pareto, 0);
  // Stratified samples through a thin lens: the error against the 64-spp reference falls.
  ASSERT_TRUE(sppRmse.count("1") && sppRmse.count("4"));
  EXPECT_LT(sppRmse["4"], sppRmse["1"]);
  std::ifstream md(dir + "/t.md");
  std::stringstream text;
  text << md.rdbuf();
  EXPECT_NE(text.str().find("Frontier"), std::string::npos);
  EXPECT_NE(text.str().find("Equal error"), std::string::npos);
}

TEST(Tradeoff, ReferenceSettingsAgainstThemselvesHaveNoError) {
  // The study's reference (robust, high, camera-relative) rendered twice: identical pixels.
  const std::string dir = scratchDir();
  std::string out;
  for (const char* name : {"a", "b"})
    ASSERT_EQ(runCommand(apertureBinary() + " render --quiet --preset exact --spp 16" +
                             kThinLensCity + " --aov all --out " + dir + "/" + name + ".exr",
                         &out),
              0)
        << out;
  EXPECT_EQ(test::differingAovs(readExr(dir + "/a.exr"), readExr(dir + "/b.exr")), "");
}

TEST(Preset, MapsToTheDocumentedSettingsAndExplicitFlagsWin) {
  const std::string dir = scratchDir();
  std::string out;
  auto render = [&](const std::string& args, const std::string& name) {
    EXPECT_EQ(runCommand(apertureBinary() + " render --quiet --size 16,12 --aov color,depth " +
                             args + " --out " + dir + "/" + name,
                         &out),
              0)
        << out;
    Imf::InputFile file((dir + "/" + name).c_str());
    return std::make_pair(file.header(), readExr(dir + "/" + name));
  };
  {
    auto [h, fb] = render("--preset fast", "fast.exr");
    EXPECT_EQ(h.compression(), Imf::NO_COMPRESSION);
    EXPECT_EQ(h.channels().findChannel("R")->type, Imf::HALF);
    EXPECT_EQ(h.channels().findChannel("Z")->type, Imf::FLOAT);
  }
  {
    ExrMetadata meta;
    render("--preset balanced", "balanced.exr");
    readExr(dir + "/balanced.exr", &meta);
    EXPECT_EQ(meta.camera.spp, 4);
  }
  {
    auto [h, fb] = render("--preset exact --spp 2 --compression piz", "exact.exr");
    ExrMetadata meta;
    readExr(dir + "/exact.exr", &meta);
    EXPECT_EQ(meta.camera.spp, 2);  // the explicit flag wins over the preset's 256
    EXPECT_EQ(h.compression(), Imf::PIZ_COMPRESSION);
    EXPECT_EQ(h.channels().findChannel("R")->type, Imf::FLOAT);
  }
  EXPECT_EQ(runCommand(apertureBinary() + " render --preset turbo --out " + dir + "/x.exr", &out),
            1);
  EXPECT_NE(out.find("known: fast, balanced, exact"), std::string::npos) << out;
  // bench takes the same presets; its JSON shows the BVH the preset chose.
  const std::string json = dir + "/b.json";
  ASSERT_EQ(runCommand(apertureBinary() +
                           " bench --quiet --preset balanced --mesh procedural:sphere "
                           "--size 32,32 --frames 1 --warmup 0 --builds 1 --json " +
                           json,
                       &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(std::ifstream(json));
  EXPECT_EQ(j["config"]["bvh_quality"], "high");
  EXPECT_EQ(j["config"]["robust"], true);
  EXPECT_EQ(j["config"]["spp"], 4);
}

TEST(BenchSweep, AovsReportsDepthAloneAndAll) {
  const std::string json = scratchDir() + "/a.json";
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() +
                           " bench --quiet --mesh procedural:sphere --size 32,32 "
                           "--frames 2 --warmup 0 --builds 1 --sweep aovs --json " +
                           json,
                       &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(std::ifstream(json));
  ASSERT_TRUE(j.contains("sweep_aovs"));
  EXPECT_GT(j["sweep_aovs"]["depth"]["mrays_per_s_median"].get<double>(), 0.0);
  EXPECT_GT(j["sweep_aovs"]["all"]["mrays_per_s_median"].get<double>(), 0.0);
  EXPECT_EQ(j["sweep_aovs"]["all"]["aovs"], "color,depth,distance,normal,position,primid,geomid");
}

TEST(Preset, JobFilesTakeThePresetAndExplicitKeysWin) {
  const std::string dir = scratchDir();
  auto job = [&](const std::string& extra) {
    const std::string path = dir + "/job.json";
    test::writeFile(path, R"({"scene": {"meshes": [{"path": "procedural:sphere"}]},
      "cameras": [{"name": "v", "eye": [0, 0, 4], "at": [0, 0, 0], "fov": 40}],
      "size": [16, 12], "output": "out/{camera}.exr")" +
                              extra + "}");
    return path;
  };
  std::string out;
  ASSERT_EQ(
      runCommand(apertureBinary() + " batch --quiet " + job(R"(, "preset": "balanced")"), &out), 0)
      << out;
  ExrMetadata meta;
  readExr(dir + "/out/v.exr", &meta);
  EXPECT_EQ(meta.camera.spp, 4);
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet " +
                           job(R"(, "preset": "exact", "spp": 2, "half": true)"),
                       &out),
            0)
      << out;
  readExr(dir + "/out/v.exr", &meta);
  EXPECT_EQ(meta.camera.spp, 2);
  Imf::InputFile file((dir + "/out/v.exr").c_str());
  EXPECT_EQ(file.header().channels().findChannel("R")->type, Imf::HALF);
  EXPECT_NE(runCommand(apertureBinary() + " batch --quiet " + job(R"(, "preset": "turbo")"), &out),
            0);
  EXPECT_NE(out.find("preset"), std::string::npos) << out;
  EXPECT_NE(out.find("known: fast, balanced, exact"), std::string::npos) << out;
}
