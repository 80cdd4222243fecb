// `aperture bench --scaling`: the sizes list, the child command line, and a small run through
// the executable whose JSON and Markdown must hold every column (no timing is checked).
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/measure/bench_scaling.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture::app {
namespace {

using test::apertureBinary;
using test::readFile;
using test::runCommand;
using test::scratchDir;

TEST(BenchScaling, SizesAreWholeTriangleCounts) {
  EXPECT_EQ(parseScalingSizes("1e5,1e6,2.5e6,300000"),
            (std::vector<uint64_t>{100000, 1000000, 2500000, 300000}));
  EXPECT_EQ(parseScalingSizes(kDefaultScalingSizes),
            (std::vector<uint64_t>{100000, 1000000, 10000000, 40000000, 100000000}));
}

TEST(BenchScaling, BadSizesNameTheValue) {
  struct Case {
    const char* text;
    const char* named;
  } cases[] = {{"1e5,abc", "'abc'"},   {"1e9", "'1e9'"},     {"99", "'99'"},     {"1e5,,1e6", "''"},
               {"1.5e2x", "'1.5e2x'"}, {"150.5", "'150.5'"}, {"-1e5", "'-1e5'"}, {"nan", "'nan'"}};
  for (const Case& c : cases) {
    try {
      parseScalingSizes(c.text);
      ADD_FAILURE() << c.text << ": no error";
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("--scaling-sizes"), std::string::npos) << msg;
      EXPECT_NE(msg.find(c.named), std::string::npos) << msg;
    }
  }
  EXPECT_THROW(parseScalingSizes(""), Error);
  EXPECT_THROW(parseScalingSizes("1e5,"), Error);
}

TEST(BenchScaling, TheSpecGeneratesTheRequestedSize) {
  // procedural.cpp promises the spheres scene within 1% of tris=N.
  for (uint64_t n : {uint64_t(10000), uint64_t(123457)}) {
    const Mesh m = loadMesh(scalingMeshSpec(n));
    EXPECT_NEAR(double(m.triangleCount()), double(n), 0.01 * double(n)) << n;
  }
}

TEST(BenchScaling, ChildArgumentsDropTheScalingFlagsAndKeepTheRest) {
  const std::vector<std::string> parent = {"bench",
                                           "--scaling",
                                           "--scaling-sizes",
                                           "1e5,1e6",
                                           "--size",
                                           "64,48",
                                           "--json=/x/out.json",
                                           "--mesh",
                                           "m.ply",
                                           "--threads",
                                           "2",
                                           "--compact",
                                           "--builds",
                                           "3",
                                           "--json",
                                           "/y/out.json",
                                           "--baseline",
                                           "--quiet",
                                           "--scaling-sizes=1e7"};
  const std::vector<std::string> child =
      scalingChildArguments(parent, 20000, true, "/tmp/row.json");
  const std::vector<std::string> expected = {"bench",
                                             "--size",
                                             "64,48",
                                             "--threads",
                                             "2",
                                             "--mesh",
                                             "procedural:spheres?tris=20000",
                                             "--baseline",
                                             "--builds",
                                             "1",
                                             "--quiet",
                                             "--json",
                                             "/tmp/row.json",
                                             "--compact"};
  EXPECT_EQ(child, expected);
  const std::vector<std::string> plain = scalingChildArguments({"bench"}, 100, false, "r.json");
  EXPECT_EQ(std::count(plain.begin(), plain.end(), "--compact"), 0);
}

/// Every row of a --scaling JSON must carry these (bench/plot.py and bench/RESULTS.md read
/// them).
const char* const kColumns[] = {"requested_triangles",
                                "triangles",
                                "compact",
                                "bvh",
                                "load_seconds",
                                "build_seconds",
                                "peak_rss_bytes",
                                "peak_rss_bytes_per_triangle",
                                "peak_rss_after_build_bytes",
                                "peak_rss_with_baseline_bytes",
                                "mesh_bytes",
                                "mesh_bytes_per_triangle",
                                "embree_bytes",
                                "embree_bytes_per_triangle",
                                "mrays_per_s",
                                "baseline_mrays_per_s",
                                "render_over_baseline",
                                "estimate_bytes",
                                "estimate_error_percent"};

TEST(BenchScalingCli, SmallRunWritesEveryColumn) {
  const std::string dir = scratchDir(), json = dir + "/scaling.json";
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() +
                           " bench --scaling --scaling-sizes 1e4,2e4 --frames 1 --warmup 0 "
                           "--size 64,48 --threads 2 --compact --json " +
                           json,
                       &out),
            0)
      << out;
  const nlohmann::json j = nlohmann::json::parse(readFile(json));
  ASSERT_TRUE(j.contains("rows")) << j.dump(2);
  const nlohmann::json& rows = j.at("rows");
  ASSERT_EQ(rows.size(), 4u) << "two sizes, then the same two with the compact BVH";
  for (size_t k = 0; k < rows.size(); ++k) {
    const nlohmann::json& r = rows[k];
    for (const char* column : kColumns)
      EXPECT_TRUE(r.contains(column)) << column << " in row " << k;
    const double requested = k % 2 == 0 ? 1e4 : 2e4;
    EXPECT_EQ(r.at("requested_triangles").get<double>(), requested);
    EXPECT_NEAR(r.at("triangles").get<double>(), requested, 0.01 * requested);
    EXPECT_EQ(r.at("compact").get<bool>(), k >= 2);
    // Resident memory holds at least the mesh buffers Embree shares, and its peak only grows.
    const double peak = r.at("peak_rss_bytes").get<double>();
    EXPECT_GE(peak, r.at("mesh_bytes").get<double>());
    EXPECT_GE(peak, r.at("peak_rss_after_build_bytes").get<double>());
    EXPECT_GE(r.at("peak_rss_with_baseline_bytes").get<double>(), peak);
    EXPECT_DOUBLE_EQ(r.at("peak_rss_bytes_per_triangle").get<double>(),
                     peak / r.at("triangles").get<double>());
    // The mesh: 12 bytes a triangle of indices and 12 a vertex of positions, never less.
    EXPECT_GE(r.at("mesh_bytes").get<double>(), 12 * r.at("triangles").get<double>());
    EXPECT_GT(r.at("embree_bytes").get<double>(), 0);
    EXPECT_GT(r.at("mrays_per_s").get<double>(), 0);
    EXPECT_GT(r.at("baseline_mrays_per_s").get<double>(), 0);
    EXPECT_DOUBLE_EQ(
        r.at("render_over_baseline").get<double>(),
        r.at("mrays_per_s").get<double>() / r.at("baseline_mrays_per_s").get<double>());
    const double estimate = r.at("estimate_bytes").get<double>();
    EXPECT_NEAR(r.at("estimate_error_percent").get<double>(), 100 * (estimate - peak) / peak, 1e-9);
  }
  EXPECT_TRUE(j.at("config").contains("cpu"));
  EXPECT_TRUE(j.at("config").contains("threads"));
  // The table beside the JSON: a header, its rule and one line a row, as on stdout.
  const std::string md = readFile(dir + "/scaling.md");
  EXPECT_EQ(std::count(md.begin(), md.end(), '\n'), 2 + 4) << md;
  EXPECT_NE(md.find("| triangles |"), std::string::npos) << md;
  EXPECT_NE(out.find(md), std::string::npos) << "stdout holds the same table";
}

TEST(BenchScalingCli, FlagMistakesAreErrors) {
  std::string out;
  EXPECT_NE(runCommand(apertureBinary() + " bench --scaling --scaling-sizes 1e4,lots", &out), 0);
  EXPECT_NE(out.find("'lots'"), std::string::npos) << out;
  EXPECT_NE(runCommand(apertureBinary() + " bench --scaling-sizes 1e4", &out), 0)
      << "--scaling-sizes without --scaling";
  EXPECT_NE(out.find("--scaling"), std::string::npos) << out;
  EXPECT_NE(runCommand(apertureBinary() + " bench --scaling --mesh procedural:cube", &out), 0);
  EXPECT_NE(out.find("--mesh"), std::string::npos) << out;
}

}  // namespace
}  // namespace aperture::app
