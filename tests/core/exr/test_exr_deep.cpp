// Deep EXR of the layered hits (core/exr/exr_deep.h): written and read back bit for bit, and read
// independently through OpenEXR's DeepScanLineInputFile for the sample counts, the order and
// the Z/ZBack convention of "Interpreting OpenEXR Deep Pixels".
#include <Imath/ImathBox.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepScanLineInputFile.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfPartType.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <vector>

#include "core/exr/exr.h"
#include "core/exr/exr_deep.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

constexpr int kWidth = 7, kHeight = 3, kLayers = 3;

/// The number of surfaces at pixel p: 0, 1, .., K in turn, so misses and full pixels occur.
unsigned surfacesAt(size_t p) { return unsigned(p % (kLayers + 1)); }

/// Layers with irregular float bits (not round numbers), nearest first, misses past them.
Framebuffer layeredFramebuffer() {
  AovSet set(kAovDepth);
  set.layers = kLayers;
  Framebuffer fb(kWidth, kHeight, set);
  const size_t n = fb.pixelCount();
  for (size_t p = 0; p < n; ++p) {
    for (unsigned k = 0; k < surfacesAt(p); ++k) {
      const size_t at = k * n + p;
      fb.layerDepth[at] = std::nextafter(1.0f + 0.37f * float(p) + 2.5f * float(k), 100.0f);
      fb.layerDistance[at] = fb.layerDepth[at] * 1.0625f + 1e-3f;
      fb.layerPrimId[at] = uint32_t(1000 * p + k);
      fb.layerGeomId[at] = k % 2;
    }
    fb.depth[p] = fb.layerDepth[p];
  }
  return fb;
}

ExrMetadata someMetadata() {
  ExrMetadata meta;
  meta.camera.type = "perspective";
  meta.camera.pixelAspectRatio = 1.0;
  meta.camera.screenWindowWidth = 2.0;
  return meta;
}

bool sameBits(const void* a, const void* b, size_t bytes) { return std::memcmp(a, b, bytes) == 0; }

TEST(ExrDeep, PathBesideTheExr) {
  EXPECT_EQ(deepLayersPath("out/render.exr"), "out/render.deep.exr");
  EXPECT_EQ(deepLayersPath("a.b/x.exr"), "a.b/x.deep.exr");
}

TEST(ExrDeep, RoundTripEqualsTheFlatLayersBitForBit) {
  const Framebuffer fb = layeredFramebuffer();
  const std::string path = test::scratchDir() + "/layers.deep.exr";
  writeDeepLayersExr(path, fb, someMetadata());
  const Framebuffer back = readDeepLayersExr(path);
  ASSERT_EQ(back.width, kWidth);
  ASSERT_EQ(back.height, kHeight);
  ASSERT_EQ(back.layers, kLayers);
  const size_t ln = fb.layerDepth.size();
  ASSERT_EQ(back.layerDepth.size(), ln);
  EXPECT_TRUE(sameBits(back.layerDepth.data(), fb.layerDepth.data(), ln * 4));
  EXPECT_TRUE(sameBits(back.layerDistance.data(), fb.layerDistance.data(), ln * 4));
  EXPECT_EQ(back.layerPrimId, fb.layerPrimId);
  EXPECT_EQ(back.layerGeomId, fb.layerGeomId);
}

TEST(ExrDeep, OpenExrSeesOneSortedPointSamplePerSurface) {
  const Framebuffer fb = layeredFramebuffer();
  const std::string path = test::scratchDir() + "/layers.deep.exr";
  writeDeepLayersExr(path, fb, someMetadata());

  // OpenEXR's own reader, samples stored pixel-major (not the layer-major trick of the writer).
  Imf::DeepScanLineInputFile file(path.c_str());
  EXPECT_EQ(file.header().type(), Imf::DEEPSCANLINE);
  const Imath::Box2i window = file.header().dataWindow();
  ASSERT_EQ(window.min.x, 0);
  ASSERT_EQ(window.max.x, kWidth - 1);
  ASSERT_EQ(window.max.y, kHeight - 1);
  const size_t n = fb.pixelCount();
  std::vector<unsigned> counts(n);
  Imf::DeepFrameBuffer frame;
  frame.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()),
                                          sizeof(unsigned), sizeof(unsigned) * kWidth));
  file.setFrameBuffer(frame);
  file.readPixelSampleCounts(0, kHeight - 1);
  for (size_t p = 0; p < n; ++p) ASSERT_EQ(counts[p], surfacesAt(p)) << "pixel " << p;

  std::vector<std::vector<float>> z(n), zBack(n), t(n);
  std::vector<std::vector<uint32_t>> prim(n), geom(n);
  std::vector<char*> zPtr(n), zBackPtr(n), tPtr(n), primPtr(n), geomPtr(n);
  for (size_t p = 0; p < n; ++p) {
    z[p].resize(counts[p]), zBack[p].resize(counts[p]), t[p].resize(counts[p]);
    prim[p].resize(counts[p]), geom[p].resize(counts[p]);
    zPtr[p] = reinterpret_cast<char*>(z[p].data());
    zBackPtr[p] = reinterpret_cast<char*>(zBack[p].data());
    tPtr[p] = reinterpret_cast<char*>(t[p].data());
    primPtr[p] = reinterpret_cast<char*>(prim[p].data());
    geomPtr[p] = reinterpret_cast<char*>(geom[p].data());
  }
  auto slice = [](Imf::PixelType type, std::vector<char*>& pointers) {
    return Imf::DeepSlice(type, reinterpret_cast<char*>(pointers.data()), sizeof(char*),
                          sizeof(char*) * kWidth, 4);
  };
  frame.insert("Z", slice(Imf::FLOAT, zPtr));
  frame.insert("ZBack", slice(Imf::FLOAT, zBackPtr));
  frame.insert("T", slice(Imf::FLOAT, tPtr));
  frame.insert("primID", slice(Imf::UINT, primPtr));
  frame.insert("geomID", slice(Imf::UINT, geomPtr));
  file.setFrameBuffer(frame);
  file.readPixelSampleCounts(0, kHeight - 1);  // a new frame buffer needs them again
  file.readPixels(0, kHeight - 1);

  for (size_t p = 0; p < n; ++p)
    for (unsigned k = 0; k < counts[p]; ++k) {
      const size_t at = k * n + p;
      EXPECT_TRUE(sameBits(&z[p][k], &fb.layerDepth[at], 4)) << p << " sample " << k;
      EXPECT_TRUE(sameBits(&zBack[p][k], &z[p][k], 4)) << "ZBack != Z at " << p << " " << k;
      EXPECT_TRUE(sameBits(&t[p][k], &fb.layerDistance[at], 4)) << p << " sample " << k;
      EXPECT_EQ(prim[p][k], fb.layerPrimId[at]);
      EXPECT_EQ(geom[p][k], fb.layerGeomId[at]);
      if (k > 0) {
        EXPECT_LT(z[p][k - 1], z[p][k]) << "not front to back at pixel " << p;
      }
    }
}

TEST(ExrDeep, FlatExrLeavesTheLayersToTheDeepFile) {
  AovSet set(kAovDepth);
  set.layers = 2;
  ExrOptions deep;
  deep.layersInDeepFile = true;
  const std::vector<std::string> flat = exrChannelNames(set), names = exrChannelNames(set, deep);
  EXPECT_EQ(names, std::vector<std::string>{"Z"});
  EXPECT_NE(std::find(flat.begin(), flat.end(), "hit1.geomID"), flat.end());

  const std::string path = test::scratchDir() + "/flat.exr";
  writeExr(path, layeredFramebuffer(), someMetadata(), deep);
  EXPECT_EQ(readExrHeader(path).channels, std::vector<std::string>{"Z"});
}

TEST(ExrDeep, ErrorsNameTheFile) {
  const std::string dir = test::scratchDir();
  const std::string missingDir = dir + "/no/such/dir/x.deep.exr";
  EXPECT_NE(test::errorOf([&] {
              writeDeepLayersExr(missingDir, layeredFramebuffer(), someMetadata());
            }).find(missingDir),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(missingDir));
  // A flat EXR is not a deep file.
  Framebuffer flat(4, 4, AovSet(kAovDepth));
  writeExr(dir + "/flat.exr", flat, someMetadata());
  const std::string message = test::errorOf([&] { readDeepLayersExr(dir + "/flat.exr"); });
  EXPECT_NE(message.find(dir + "/flat.exr"), std::string::npos) << message;
  // No layers, nothing to write.
  EXPECT_NE(test::errorOf([&] { writeDeepLayersExr(dir + "/none.exr", flat, {}); }).find("none"),
            std::string::npos);
}

}  // namespace
}  // namespace aperture
