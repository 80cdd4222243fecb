// The speed/accuracy study (bench/measure/tradeoff.h, `aperture tradeoff`) through the
// executable: a quick study covers every knob and more samples reduce the error, and the
// reference settings against themselves have none.
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
