// The presets (apps/services/presets.h) through the executable: --preset maps to the documented
// settings and explicit flags win, and job files take "preset" with their explicit keys winning.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/exr/exr.h"
#include "tests/support.h"

using namespace aperture;
using aperture::test::apertureBinary;
using aperture::test::runCommand;
using aperture::test::scratchDir;

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
  const std::string jsonPath = dir + "/b.json";
  ASSERT_EQ(runCommand(apertureBinary() +
                           " bench --quiet --preset balanced --mesh procedural:sphere "
                           "--size 32,32 --frames 1 --warmup 0 --builds 1 --json " +
                           jsonPath,
                       &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(std::ifstream(jsonPath));
  EXPECT_EQ(j["config"]["bvh_quality"], "high");
  EXPECT_EQ(j["config"]["robust"], true);
  EXPECT_EQ(j["config"]["spp"], 4);
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
