// --layers on the command line and in jobs (issue 12 item 5): the documented EXR channels,
// read back equal to the geometry AOVs for layer 0 and ordered in depth after it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "core/exr/exr.h"
#include "core/exr/exr_deep.h"
#include "tests/support.h"

namespace aperture {
namespace {

// Two spheres along the view axis: up to four surfaces per ray.
const char* const kScene =
    " --mesh 'procedural:sphere?radius=1&cz=1.5' --mesh 'procedural:sphere?radius=1&cz=-1.5'";

void expectLayeredFile(const std::string& path, int layers) {
  ExrHeader header = readExrHeader(path);
  for (int k = 0; k < layers; ++k)
    for (const char* c : {"Z", "T", "primID", "geomID"}) {
      const std::string name = "hit" + std::to_string(k) + "." + c;
      EXPECT_NE(std::find(header.channels.begin(), header.channels.end(), name),
                header.channels.end())
          << name << " missing in " << path;
    }
  EXPECT_EQ(std::find(header.channels.begin(), header.channels.end(),
                      "hit" + std::to_string(layers) + ".Z"),
            header.channels.end());
  const Framebuffer fb = readExr(path);
  ASSERT_EQ(fb.layers, layers);
  const size_t n = fb.pixelCount();
  int deep = 0;
  for (size_t p = 0; p < n; ++p) {
    // Layer 0 is the Z AOV, bit for bit; later layers lie farther, or are misses.
    EXPECT_EQ(std::memcmp(&fb.layerDepth[p], &fb.depth[p], 4), 0) << p;
    for (int k = 1; k < layers; ++k) {
      const float z = fb.layerDepth[size_t(k) * n + p],
                  before = fb.layerDepth[size_t(k - 1) * n + p];
      EXPECT_GE(z, before) << p << " layer " << k;
      if (std::isinf(z)) {
        EXPECT_EQ(fb.layerGeomId[size_t(k) * n + p], 0xFFFFFFFFu);
      }
    }
    deep += std::isfinite(fb.layerDepth[size_t(layers - 1) * n + p]);
  }
  EXPECT_GT(deep, 0) << "no ray crossed " << layers << " surfaces";
}

TEST(LayersCli, RenderWritesTheDocumentedChannels) {
  const std::string dir = test::scratchDir();
  std::string out;
  const std::string cmd = test::apertureBinary() + " render" + kScene +
                          " --eye 0,0,8 --at 0,0,0 --fov 30 --size 40,32 --aov depth --layers 3 "
                          "--out " +
                          dir + "/a.exr";
  ASSERT_EQ(test::runCommand(cmd, &out), 0) << out;
  expectLayeredFile(dir + "/a.exr", 3);
  // Both methods give the same file here (no coincident surfaces).
  ASSERT_EQ(test::runCommand("APERTURE_LAYERS_METHOD=retrace " + cmd + "-retrace.exr", &out), 0)
      << out;
  EXPECT_EQ(test::differingAovs(readExr(dir + "/a.exr"), readExr(dir + "/a.exr-retrace.exr")), "");
  const Framebuffer a = readExr(dir + "/a.exr"), b = readExr(dir + "/a.exr-retrace.exr");
  EXPECT_TRUE(a.layerDepth == b.layerDepth && a.layerPrimId == b.layerPrimId &&
              a.layerGeomId == b.layerGeomId);
}

TEST(LayersCli, BadCountsAreRefused) {
  std::string out;
  for (const char* k : {"0", "65"}) {
    EXPECT_NE(test::runCommand(test::apertureBinary() + " render --size 8,8 --layers " + k +
                                   " --out " + test::scratchDir() + "/x.exr",
                               &out),
              0);
    EXPECT_NE(out.find("--layers " + std::string(k) + " must be in [1, 64]"), std::string::npos)
        << out;
  }
}

TEST(LayersCli, JobKeyLayers) {
  const std::string dir = test::scratchDir();
  test::writeFile(dir + "/job.json", R"({
    "scene": {"meshes": [{"path": "procedural:sphere?radius=1&cz=1.5"},
                         {"path": "procedural:sphere?radius=1&cz=-1.5"}]},
    "cameras": [{"name": "a", "eye": [0, 0, 8], "at": [0, 0, 0], "fov": 30}],
    "size": [40, 32], "aovs": "depth", "layers": 4, "output": ")" +
                                         dir + R"(/out/{camera}.exr"})");
  std::string out;
  ASSERT_EQ(test::runCommand(test::apertureBinary() + " batch " + dir + "/job.json", &out), 0)
      << out;
  expectLayeredFile(dir + "/out/a.exr", 4);
  test::writeFile(dir + "/bad.json", R"({"scene": {"meshes": [{"path": "procedural:sphere"}]},
    "cameras": [{"name": "a", "eye": [0, 0, 8], "at": [0, 0, 0]}], "layers": 99,
    "output": ")" + dir + R"(/bad/{camera}.exr"})");
  EXPECT_NE(test::runCommand(test::apertureBinary() + " batch " + dir + "/bad.json", &out), 0);
  EXPECT_NE(out.find("layers"), std::string::npos) << out;
  EXPECT_NE(out.find("99"), std::string::npos) << out;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(LayersCli, DeepWritesTheLayersBesideTheExr) {
  const std::string dir = test::scratchDir();
  const std::string base = test::apertureBinary() + " render" + kScene +
                           " --eye 0,0,8 --at 0,0,0 --fov 30 --size 40,32 --aov depth --layers 3";
  std::string out;
  ASSERT_EQ(test::runCommand(base + " --deep --out " + dir + "/out.exr", &out), 0) << out;
  ASSERT_EQ(test::runCommand(base + " --out " + dir + "/flat.exr", &out), 0) << out;
  EXPECT_EQ(readExrHeader(dir + "/out.exr").channels, std::vector<std::string>{"Z"});
  const Framebuffer deep = readDeepLayersExr(dir + "/out.deep.exr"),
                    flat = readExr(dir + "/flat.exr");
  ASSERT_EQ(deep.layers, 3);
  ASSERT_EQ(flat.layers, 3);
  EXPECT_TRUE(sameBits(deep.layerDepth, flat.layerDepth));
  EXPECT_TRUE(sameBits(deep.layerDistance, flat.layerDistance));
  EXPECT_EQ(deep.layerPrimId, flat.layerPrimId);
  EXPECT_EQ(deep.layerGeomId, flat.layerGeomId);
  EXPECT_TRUE(std::any_of(flat.layerDepth.begin() + 2 * flat.pixelCount(), flat.layerDepth.end(),
                          [](float z) { return std::isfinite(z); }))
      << "no pixel with 3 surfaces: the comparison would not cover full pixels";

  EXPECT_NE(test::runCommand(
                test::apertureBinary() + " render --size 8,8 --deep --out " + dir + "/x.exr", &out),
            0);
  EXPECT_NE(out.find("--deep needs --layers"), std::string::npos) << out;
}

TEST(LayersCli, JobKeyDeepAndResume) {
  const std::string dir = test::scratchDir();
  const std::string job = R"({
    "scene": {"meshes": [{"path": "procedural:sphere?radius=1&cz=1.5"},
                         {"path": "procedural:sphere?radius=1&cz=-1.5"}]},
    "cameras": [{"name": "a", "eye": [0, 0, 8], "at": [0, 0, 0], "fov": 30}],
    "size": [40, 32], "aovs": "depth", "layers": 2, "deep": true, "output": ")" +
                          dir + R"(/out/{camera}.exr"})";
  test::writeFile(dir + "/job.json", job);
  const std::string batch = test::apertureBinary() + " batch " + dir + "/job.json";
  std::string out;
  ASSERT_EQ(test::runCommand(batch, &out), 0) << out;
  EXPECT_EQ(readExrHeader(dir + "/out/a.exr").channels, std::vector<std::string>{"Z"});
  EXPECT_EQ(readDeepLayersExr(dir + "/out/a.deep.exr").layers, 2);
  // --resume keeps a complete image and renders again one whose deep file is gone.
  const auto written = std::filesystem::last_write_time(dir + "/out/a.exr");
  ASSERT_EQ(test::runCommand(batch + " --resume", &out), 0) << out;
  EXPECT_EQ(std::filesystem::last_write_time(dir + "/out/a.exr"), written);
  std::filesystem::remove(dir + "/out/a.deep.exr");
  ASSERT_EQ(test::runCommand(batch + " --resume", &out), 0) << out;
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/a.deep.exr")) << out;

  std::string noLayers = job;
  noLayers.replace(noLayers.find("\"layers\": 2, "), 13, "");
  test::writeFile(dir + "/bad.json", noLayers);
  EXPECT_NE(test::runCommand(test::apertureBinary() + " batch " + dir + "/bad.json", &out), 0);
  EXPECT_NE(out.find("\"deep\": true needs \"layers\""), std::string::npos) << out;
}

}  // namespace
}  // namespace aperture
