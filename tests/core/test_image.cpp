// PNG previews and framebuffer comparison.
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <vector>

#include "core/error.h"
#include "core/image.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;

struct Png {
  int width = 0, height = 0, channels = 0;
  OIIO::TypeDesc format;
  std::vector<uint8_t> pixels;
  const uint8_t* at(int row, int col) const {
    return &pixels[(size_t(row) * width + col) * size_t(channels)];
  }
};

Png readPng(const std::string& path) {
  Png png;
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // the file's bytes, not premultiplied ones
  auto in = OIIO::ImageInput::open(path, &config);
  EXPECT_TRUE(in) << OIIO::geterror();
  if (!in) return png;
  const OIIO::ImageSpec& spec = in->spec();
  png.width = spec.width;
  png.height = spec.height;
  png.channels = spec.nchannels;
  png.format = spec.format;
  EXPECT_EQ(std::string(in->format_name()), "png");
  png.pixels.resize(size_t(png.width) * png.height * png.channels);
  EXPECT_TRUE(in->read_image(0, 0, 0, -1, OIIO::TypeDesc::UINT8, png.pixels.data()))
      << in->geterror();
  in->close();
  return png;
}

/// sRGB byte of a linear value, written out independently of core/image.cpp.
int srgbByte(double linear) {
  double v = linear < 0 ? 0 : linear > 1 ? 1 : linear;
  v = v <= 0.0031308 ? v * 12.92 : 1.055 * std::exp(std::log(v) / 2.4) - 0.055;
  return int(std::floor(v * 255.0 + 0.5));
}

size_t fileCount(const std::string& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(Preview, ColorIsSrgbEncodedWithAlpha) {
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/preview.png";
  Framebuffer fb(7, 5, kAovColor);
  const size_t probe = 2 * 7 + 3;  // row 2, column 3
  const float values[4] = {0.5f, 0.2f, 0.0021f, 0.75f};
  for (int c = 0; c < 4; ++c) fb.rgba[4 * probe + c] = values[c];
  const size_t bright = 4 * 7 + 6;  // out of range values clamp
  fb.rgba[4 * bright + 0] = 3.0f;
  fb.rgba[4 * bright + 1] = -1.0f;
  fb.rgba[4 * bright + 2] = 1.0f;
  fb.rgba[4 * bright + 3] = 1.0f;
  writePreview(path, fb);
  EXPECT_EQ(fileCount(dir), 1u);

  const Png png = readPng(path);
  EXPECT_EQ(png.width, 7);
  EXPECT_EQ(png.height, 5);
  ASSERT_EQ(png.channels, 4);
  EXPECT_EQ(png.format, OIIO::TypeDesc::UINT8);
  const uint8_t* p = png.at(2, 3);
  EXPECT_EQ(p[0], srgbByte(0.5));
  EXPECT_EQ(p[1], srgbByte(0.2));
  EXPECT_EQ(p[2], srgbByte(0.0021));
  EXPECT_EQ(p[3], int(std::floor(0.75 * 255 + 0.5)));  // alpha is not encoded
  const uint8_t* b = png.at(4, 6);
  EXPECT_EQ(b[0], 255);
  EXPECT_EQ(b[1], 0);
  EXPECT_EQ(b[2], 255);
  EXPECT_EQ(b[3], 255);
  const uint8_t* zero = png.at(0, 0);
  EXPECT_EQ(zero[0] + zero[1] + zero[2] + zero[3], 0);
}

TEST(Preview, DepthAsGreyWhenNoColor) {
  const std::string path = test::scratchDir() + "/depth.png";
  Framebuffer fb(4, 1, kAovDepth | kAovNormal);
  fb.depth = {2.0f, 4.0f, 10.0f, std::numeric_limits<float>::infinity()};
  writePreview(path, fb);
  const Png png = readPng(path);
  ASSERT_EQ(png.channels, 3);
  ASSERT_EQ(png.width, 4);
  const int expected[4] = {255, int(std::floor(255.0 * 6 / 8 + 0.5)), 0, 0};
  for (int col = 0; col < 4; ++col)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(png.at(0, col)[c], expected[col]) << col;
}

TEST(Preview, NormalsWhenNoColorOrDepth) {
  const std::string path = test::scratchDir() + "/normal.png";
  Framebuffer fb(2, 1, kAovNormal);
  fb.normal = {0.0f, 0.0f, 1.0f, -1.0f, 0.6f, -0.8f};
  writePreview(path, fb);
  const Png png = readPng(path);
  ASSERT_EQ(png.channels, 3);
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(png.pixels[i], int(std::floor((fb.normal[i] * 0.5 + 0.5) * 255 + 0.5))) << i;
}

TEST(Preview, ErrorsNameThePath) {
  const std::string dir = test::scratchDir();
  EXPECT_THROW(writePreview(dir + "/ids.png", Framebuffer(2, 2, kAovPrimId)), Error);
  try {
    writePreview(dir + "/missing/p.png", Framebuffer(2, 2, kAovColor));
    FAIL() << "no error for a missing directory";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/missing"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fileCount(dir), 0u);
}

Framebuffer colorRamp(int w, int h) {
  Framebuffer fb(w, h, kAovColor | kAovPrimId | kAovDepth);
  for (size_t i = 0; i < fb.pixelCount(); ++i) {
    for (int c = 0; c < 4; ++c) fb.rgba[4 * i + c] = 0.05f * float(i % 11) + 0.1f * float(c);
    fb.primId[i] = uint32_t(i);
    fb.depth[i] = 1.0f + float(i);
  }
  return fb;
}

TEST(Compare, IdenticalImages) {
  const Framebuffer a = colorRamp(6, 5);
  const ImageDiff d = compareFramebuffers(a, a);
  EXPECT_EQ(d.rmse, 0.0);
  EXPECT_TRUE(std::isinf(d.psnr) && d.psnr > 0) << d.psnr;
  EXPECT_EQ(d.maxError, 0.0);
  EXPECT_EQ(d.meanError, 0.0);
  EXPECT_EQ(d.primIdMismatch, 0.0);
  EXPECT_EQ(d.depthRelError, 0.0);
}

TEST(Compare, ConstantOffsetGivesClosedFormErrors) {
  const Framebuffer ref = colorRamp(8, 4);
  Framebuffer test = ref;
  const double offset = 0.125;
  const double tol = 1e-6;  // the offset is added in float
  for (size_t i = 0; i < test.pixelCount(); ++i) test.rgba[4 * i] += float(offset);  // R only
  // One channel of four off by `offset`: rmse = sqrt(offset^2 / 4), mean = offset / 4.
  const ImageDiff d = compareFramebuffers(test, ref, 2.0);
  EXPECT_NEAR(d.rmse, offset / 2, tol);
  EXPECT_NEAR(d.meanError, offset / 4, tol);
  EXPECT_NEAR(d.maxError, offset, tol);
  EXPECT_NEAR(d.psnr, 20 * std::log10(2.0 / (offset / 2)), 1e-6);

  for (size_t i = 0; i < test.rgba.size(); ++i) test.rgba[i] = ref.rgba[i] + float(offset);
  const ImageDiff all = compareFramebuffers(test, ref);
  EXPECT_NEAR(all.rmse, offset, tol);
  EXPECT_NEAR(all.psnr, 20 * std::log10(1.0 / offset), 1e-6);
}

TEST(Compare, PrimIdMismatchShare) {
  const Framebuffer ref = colorRamp(4, 2);
  Framebuffer test = ref;
  test.primId[1] = 77;
  test.primId[4] = kInvalidId;
  test.primId[7] = 0;
  EXPECT_DOUBLE_EQ(compareFramebuffers(test, ref).primIdMismatch, 3.0 / 8.0);
  Framebuffer noIds(4, 2, kAovColor);
  EXPECT_EQ(compareFramebuffers(noIds, ref).primIdMismatch, 0.0);
}

TEST(Compare, DepthOnlyImages) {
  const float inf = std::numeric_limits<float>::infinity();
  Framebuffer ref(4, 1, kAovDepth), test(4, 1, kAovDepth);
  ref.depth = {2.0f, 4.0f, inf, 8.0f};
  test.depth = {2.5f, 4.0f, inf, 6.0f};
  const ImageDiff d = compareFramebuffers(test, ref);
  EXPECT_NEAR(d.depthRelError, (0.25 + 0.0 + 0.25) / 3.0, 1e-9);
  EXPECT_NEAR(d.rmse, std::sqrt((0.25 + 4.0) / 4.0), 1e-9);  // misses in both count as equal
  EXPECT_NEAR(d.maxError, 2.0, 1e-9);
}

TEST(Compare, SizeMismatchThrows) {
  EXPECT_THROW(compareFramebuffers(colorRamp(4, 2), colorRamp(2, 4)), Error);
  EXPECT_THROW(compareFramebuffers(Framebuffer(2, 2, kAovPrimId), Framebuffer(2, 2, kAovPrimId)),
               Error);
}

}  // namespace
}  // namespace aperture
