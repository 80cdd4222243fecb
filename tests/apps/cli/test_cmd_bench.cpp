// `aperture bench` (apps/cli/cmd_bench.cpp) through the executable: --sweep aovs reports the
// depth AOV alone and every AOV.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support.h"

using aperture::test::apertureBinary;
using aperture::test::runCommand;
using aperture::test::scratchDir;

TEST(BenchSweep, AovsReportsDepthAloneAndAll) {
  const std::string jsonPath = scratchDir() + "/a.json";
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() +
                           " bench --quiet --mesh procedural:sphere --size 32,32 "
                           "--frames 2 --warmup 0 --builds 1 --sweep aovs --json " +
                           jsonPath,
                       &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(std::ifstream(jsonPath));
  ASSERT_TRUE(j.contains("sweep_aovs"));
  EXPECT_GT(j["sweep_aovs"]["depth"]["mrays_per_s_median"].get<double>(), 0.0);
  EXPECT_GT(j["sweep_aovs"]["all"]["mrays_per_s_median"].get<double>(), 0.0);
  EXPECT_EQ(j["sweep_aovs"]["all"]["aovs"], "color,depth,distance,normal,position,primid,geomid");
}
