// Documented bounds (size, spp, threads, tile, packet) checked before anything is loaded or
// allocated, and the --max-memory estimate and refusal.
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <string>

#include "core/error.h"
#include "core/limits.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::apertureBinary;
using test::runCommand;
using test::scratchDir;
using test::writeFile;

double secondsOf(const std::function<void()>& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST(Limits, PlyHeaderGivesCountsWithoutReadingTheData) {
  const std::string path = scratchDir() + "/m.ply";
  // 1000 float vertices and 500 quads (binary): 12000 + 500 * 17 bytes of data.
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
      "property float y\nproperty float z\nelement face 500\n"
      "property list uchar int vertex_indices\nend_header\n";
  s += std::string(12000 + 500 * 17, '\0');
  writeFile(path, s);
  const MeshSizeEstimate m = estimateMeshSize(path);
  EXPECT_EQ(m.vertices, 1000u);
  EXPECT_EQ(m.triangles, 1000u) << "quads are two triangles each";
  EXPECT_EQ(m.fileBytes, s.size());
  EXPECT_EQ(m.how, "PLY header");
}

TEST(Limits, PlyCountsLargerThanTheFileAreClamped) {
  const std::string path = scratchDir() + "/m.ply";
  writeFile(path,
            "ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\n"
            "property float y\nproperty float z\nelement face 1000000000000\n"
            "property list uchar int vertex_indices\nend_header\n0 0 0\n");
  const MeshSizeEstimate m = estimateMeshSize(path);
  EXPECT_LE(m.vertices, 10u);
  EXPECT_LE(m.triangles, 10u);
}

TEST(Limits, ObjSampleFindsFacesAfterAllTheVertices) {
  const std::string path = scratchDir() + "/m.obj";
  std::string s;
  const int n = 100000;  // ~3 MB: sampled, not read whole
  for (int i = 0; i < n; ++i) s += "v 0.123456 0.234567 0.345678\n";
  for (int i = 1; i + 2 <= n; ++i)
    s +=
        "f " + std::to_string(i) + " " + std::to_string(i + 1) + " " + std::to_string(i + 2) + "\n";
  writeFile(path, s);
  const MeshSizeEstimate m = estimateMeshSize(path);
  EXPECT_GT(m.triangles, uint64_t(n) / 3);
  EXPECT_LT(m.triangles, uint64_t(n) * 3);
  EXPECT_GT(m.vertices, uint64_t(n) / 3);
  EXPECT_LT(m.vertices, uint64_t(n) * 3);
}

TEST(Limits, ProceduralSpecAndMissingFiles) {
  EXPECT_EQ(estimateMeshSize("procedural:spheres?tris=5000000").triangles, 5000000u);
  EXPECT_EQ(estimateMeshSize("procedural:sphere?segments=10&rings=5").triangles, 100u);
  const MeshSizeEstimate missing = estimateMeshSize("/nonexistent/x.ply");
  EXPECT_EQ(missing.triangles, 0u) << "left to the loader, which names the problem";
}

TEST(Limits, FramebufferBytesFollowTheAovs) {
  EXPECT_EQ(framebufferBytesPerPixel(kAovColor), 16u);
  EXPECT_EQ(framebufferBytesPerPixel(parseAovList("all")), 56u);
  const MemoryEstimate e = estimateMemory({"procedural:quad"}, 1000, 1000, kAovDepth);
  EXPECT_EQ(e.framebufferBytes, 4000000u);
  EXPECT_EQ(e.bvhBytes, 2 * kBvhBytesPerTriangle);
}

TEST(Limits, MemoryLimitParsing) {
  EXPECT_EQ(parseMemoryLimit("--max-memory", ""), 0u);
  EXPECT_EQ(parseMemoryLimit("--max-memory", "4096"), 4096u);
  EXPECT_EQ(parseMemoryLimit("--max-memory", "2K"), 2048u);
  EXPECT_EQ(parseMemoryLimit("--max-memory", "1.5G"), 1536ull << 20);
  EXPECT_EQ(parseMemoryLimit("--max-memory", "3MiB"), 3ull << 20);
  EXPECT_GT(parseMemoryLimit("--max-memory", "auto"), 0u);
  for (const char* bad : {"0", "-5", "x", "1Q", "nan", "1e30"})
    EXPECT_THROW(parseMemoryLimit("--max-memory", bad), Error) << bad;
}

TEST(Limits, MemoryCheckNamesTheEstimateAndTheLimit) {
  MemoryEstimate e;
  e.bvhBytes = 5000000000;
  try {
    checkMemoryLimit(e, 1000000000, "--max-memory", "1G");
    FAIL() << "no error";
  } catch (const Error& err) {
    const std::string msg = err.what();
    EXPECT_NE(msg.find("5.00 GB"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1.00 GB"), std::string::npos) << msg;
    EXPECT_NE(msg.find("--max-memory 1G"), std::string::npos) << msg;
  }
  EXPECT_NO_THROW(checkMemoryLimit(e, 0, "--max-memory", ""));
}

TEST(LimitsCli, MaxMemoryRefusesBeforeLoading) {
  const std::string exr = scratchDir() + "/x.exr";
  std::string out;
  int rc = 0;
  // 400M triangles would take minutes and ~40 GB to load and build; refusing takes no time.
  const double s = secondsOf([&] {
    rc = runCommand(apertureBinary() + " render --max-memory 2G --out " + exr +
                        " --mesh 'procedural:spheres?tris=400000000'",
                    &out);
  });
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("needs about"), std::string::npos) << out;
  EXPECT_NE(out.find("--max-memory 2G"), std::string::npos) << out;
  EXPECT_LT(s, 2.0);
  EXPECT_FALSE(test::fileExists(exr));
  // The framebuffers alone: 65536 x 4096 x all AOVs is 15 GB.
  EXPECT_EQ(runCommand(apertureBinary() +
                           " render --max-memory 1G --size 65536,4096 --aov all "
                           "--out " +
                           exr,
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("framebuffers 15"), std::string::npos) << out;
  EXPECT_EQ(runCommand(apertureBinary() + " bench --max-memory 1M --frames 1 --warmup 0", &out), 1)
      << out;
  EXPECT_NE(out.find("--max-memory 1M"), std::string::npos) << out;
  // Within the limit it renders.
  EXPECT_EQ(
      runCommand(apertureBinary() + " render --quiet --max-memory 4G --size 32,32 --out " + exr,
                 &out),
      0)
      << out;
  EXPECT_TRUE(test::fileExists(exr));
}

/// Every documented bound, and absurd values, fail at once: exit 1 or 2, a message naming the
/// flag, no output file. The mesh is a 400M-triangle procedural scene, so a check that ran
/// after loading would take minutes instead of milliseconds.
TEST(LimitsCli, AbsurdValuesAreErrorsBeforeAnyAllocation) {
  const std::string dir = scratchDir(), exr = dir + "/x.exr";
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--size 0,10", "--size"},
      {"--size 10,0", "--size"},
      {"--size -5,10", "--size"},
      {"--size 65537,1", "--size"},
      {"--size 1000000000,1000000000", "--size"},
      {"--size 65536,65536", "--size"},  // 2^32 pixels: each side fits, the total does not
      {"--size 16384,16385", "--size"},  // 2^28 + 16384 pixels
      {"--size 10.5,10", "--size"},
      {"--size 1e9,1e9", "--size"},
      {"--spp 0", "--spp: 0: must be in [1, 65536]"},
      {"--spp -1", "--spp: -1: must be in [1, 65536]"},
      {"--spp 65537", "--spp: 65537: must be in [1, 65536]"},
      {"--spp 1000000000", "--spp: 1000000000: must be in [1, 65536]"},
      {"--threads -1", "--threads -1"},
      {"--threads 4097", "--threads 4097"},
      {"--threads 1000000000000", "--threads"},
      {"--tile 0", "tile size 0"},
      {"--tile -4", "tile size -4"},
      {"--tile 6", "tile size 6"},
      {"--tile 4100", "tile size 4100"},
      {"--packet 0", "packet width 0"},
      {"--packet 32", "packet width 32"},
      {"--packet -16", "packet width -16"},
  };
  for (const Case& c : cases) {
    std::string out;
    int rc = 0;
    const double s = secondsOf([&] {
      rc = runCommand(apertureBinary() +
                          " render --mesh 'procedural:spheres?tris=400000000' --out " + exr + " " +
                          c.args,
                      &out);
    });
    EXPECT_TRUE(rc == 1 || rc == 2) << c.args << ": exit " << rc << "\n" << out;
    EXPECT_NE(out.find(c.expect), std::string::npos) << c.args << "\n" << out;
    EXPECT_LT(s, 2.0) << c.args << ": checked after loading?";
    EXPECT_FALSE(test::fileExists(exr)) << c.args;
  }
}

TEST(LimitsCli, HelpDocumentsTheBounds) {
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " render --help", &out), 0);
  for (const char* s : {"[1, 65536]", "2^28 pixels", "[0, 4096]", "multiple of 4 in [4, 4096]",
                        "1, 4, 8 or 16", "--max-memory"})
    EXPECT_NE(out.find(s), std::string::npos) << s;
}

}  // namespace
}  // namespace aperture
