// --layers on the command line and in jobs (issue 12 item 5): the documented EXR channels,
// read back equal to the geometry AOVs for layer 0 and ordered in depth after it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/exr.h"
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

}  // namespace
}  // namespace aperture
