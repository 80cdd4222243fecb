// PNG previews and framebuffer comparison.

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <vector>

#include "core/io/image.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;

struct Png {
  int width = 0, height = 0, channels = 0;
  std::optional<SampleType> type;
  std::string description;  ///< ImageDescription
  std::vector<uint8_t> pixels;
  const uint8_t* at(int row, int col) const {
    return &pixels[(size_t(row) * width + col) * size_t(channels)];
  }
  std::array<int, 3> rgb(int row, int col) const {
    const uint8_t* p = at(row, col);
    return {p[0], p[1], p[2]};
  }
};

Png readPng(const std::string& path) {
  const test::DecodedImage<uint8_t> file = test::readImageFile<uint8_t>(path);
  EXPECT_EQ(file.info.format, "png") << path;
  return {file.info.width, file.info.height,      file.info.channels,
          file.info.type,  file.info.description, file.samples};
}

/// sRGB byte of a linear value, written out independently of core/io/image.cpp.
int srgbByte(double linear) {
  double v = linear < 0 ? 0 : linear > 1 ? 1 : linear;
  v = v <= 0.0031308 ? v * 12.92 : 1.055 * std::exp(std::log(v) / 2.4) - 0.055;
  return int(std::floor(v * 255.0 + 0.5));
}

/// Linear value of an sRGB byte (IEC 61966-2-1), for the background composite.
double linearOfByte(int byte) {
  const double v = byte / 255.0;
  return v <= 0.04045 ? v / 12.92 : std::exp(2.4 * std::log((v + 0.055) / 1.055));
}

const std::array<int, 3> kBackground = {kPreviewBackground[0], kPreviewBackground[1],
                                        kPreviewBackground[2]};

size_t fileCount(const std::string& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(Preview, ColorIsOpaqueSrgbOverTheBackground) {
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/preview.png";
  Framebuffer fb(7, 5, kAovColor);
  const size_t probe = 2 * 7 + 3;  // row 2, column 3: three quarters covered
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
  ASSERT_EQ(png.channels, 3) << "an opaque preview has no alpha channel";
  EXPECT_EQ(png.type, SampleType::UInt8);
  // The color AOV is premultiplied by coverage: c + (1 - A) * background, in linear light.
  for (int c = 0; c < 3; ++c) {
    const int composite = srgbByte(values[c] + 0.25 * linearOfByte(kBackground[size_t(c)]));
    EXPECT_EQ(png.at(2, 3)[c], composite) << c;
  }
  // Without the composite (the old transparent preview's bytes) blue would be much darker.
  EXPECT_GT(png.at(2, 3)[2], srgbByte(values[2]) + 10);
  EXPECT_EQ(png.rgb(4, 6), (std::array<int, 3>{255, 0, 255}));
  EXPECT_EQ(png.rgb(0, 0), kBackground) << "a miss shows the background";
  EXPECT_NE(png.rgb(0, 0), (std::array<int, 3>{0, 0, 0}));
  EXPECT_NE(png.description.find("color"), std::string::npos) << png.description;
}

TEST(Preview, DepthPerImageRangeWithoutOptions) {
  const std::string path = test::scratchDir() + "/depth.png";
  Framebuffer fb(4, 1, kAovDepth | kAovNormal);
  fb.depth = {2.0f, 4.0f, 10.0f, std::numeric_limits<float>::infinity()};
  writePreview(path, fb);
  const Png png = readPng(path);
  ASSERT_EQ(png.channels, 3);
  ASSERT_EQ(png.width, 4);
  const int expected[3] = {255, int(std::floor(255.0 * 6 / 8 + 0.5)), 0};
  for (int col = 0; col < 3; ++col)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(png.at(0, col)[c], expected[col]) << col;
  EXPECT_EQ(png.rgb(0, 3), kBackground);
}

TEST(Preview, DepthWithFixedRangeMapsNearToWhiteAndFarToBlack) {
  const std::string dir = test::scratchDir();
  const double nearZ = 2, farZ = 10;
  const float inf = std::numeric_limits<float>::infinity();
  Framebuffer fb(6, 1, kAovDepth);
  fb.depth = {2.0f, 10.0f, 4.0f, 1.0f, 25.0f, inf};
  PreviewOptions options;
  options.depthRange = glm::dvec2(nearZ, farZ);
  writePreview(dir + "/fixed.png", fb, options);
  const Png png = readPng(dir + "/fixed.png");
  ASSERT_EQ(png.channels, 3);
  // Documented: NEAR -> 255 (white), FAR -> 0 (black), linear between, clamped outside.
  const int expected[5] = {255, 0, int(std::floor(255.0 * (farZ - 4) / (farZ - nearZ) + 0.5)), 255,
                           0};
  for (int col = 0; col < 5; ++col) {
    EXPECT_EQ(png.rgb(0, col), (std::array<int, 3>{expected[col], expected[col], expected[col]}))
        << "depth " << fb.depth[size_t(col)];
  }
  // The opposite convention (NEAR black) would put 0 at NEAR and 255 at FAR.
  EXPECT_NE(png.at(0, 0)[0], 0);
  EXPECT_NE(png.at(0, 1)[0], 255);
  EXPECT_EQ(png.rgb(0, 5), kBackground);
  EXPECT_NE(png.description.find("2 white to 10 black (fixed range)"), std::string::npos)
      << png.description;

  // A second image with other depths: the same depth gets the same grey (no flicker), which
  // the image's own range would not give (its nearest depth, 4, would be white).
  Framebuffer other(2, 1, kAovDepth);
  other.depth = {4.0f, 8.0f};
  writePreview(dir + "/other.png", other, options);
  const Png second = readPng(dir + "/other.png");
  EXPECT_EQ(second.at(0, 0)[0], expected[2]);
  EXPECT_NE(expected[2], 255);
  writePreview(dir + "/own.png", other);
  EXPECT_EQ(readPng(dir + "/own.png").at(0, 0)[0], 255) << "per-image range without options";
}

TEST(Preview, NormalsWhenNoColorOrDepth) {
  const std::string path = test::scratchDir() + "/normal.png";
  Framebuffer fb(3, 1, kAovNormal);
  fb.normal = {0.0f, 0.0f, 1.0f, -1.0f, 0.6f, -0.8f, 0.0f, 0.0f, 0.0f};
  writePreview(path, fb);
  const Png png = readPng(path);
  ASSERT_EQ(png.channels, 3);
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(png.pixels[i], int(std::floor((fb.normal[i] * 0.5 + 0.5) * 255 + 0.5))) << i;
  EXPECT_EQ(png.rgb(0, 2), kBackground) << "a miss (zero normal) shows the background";
}

/// Every pixel of an ID preview: equal IDs give equal colours, different IDs different
/// colours, misses the background, and no ID the background.
void expectHashedIdColours(const Png& png, const std::vector<uint32_t>& ids) {
  std::map<uint32_t, std::array<int, 3>> colourOf;
  std::map<std::array<int, 3>, uint32_t> idOf;
  for (int row = 0; row < png.height; ++row)
    for (int col = 0; col < png.width; ++col) {
      const uint32_t id = ids[size_t(row) * size_t(png.width) + size_t(col)];
      const std::array<int, 3> c = png.rgb(row, col);
      if (id == kInvalidId) {
        EXPECT_EQ(c, kBackground) << "miss at " << row << "," << col;
        continue;
      }
      EXPECT_NE(c, kBackground) << "ID " << id;
      auto [known, fresh] = colourOf.emplace(id, c);
      EXPECT_EQ(known->second, c) << "ID " << id << " in two colours";
      auto [owner, first] = idOf.emplace(c, id);
      EXPECT_EQ(owner->second, id) << "IDs " << id << " and " << owner->second << " share a colour";
    }
  EXPECT_GT(colourOf.size(), 1u);
}

TEST(Preview, PrimIdsGetHashedColoursAndMissesTheBackground) {
  const std::string dir = test::scratchDir();
  // 2x2 blocks of one ID, neighbouring blocks consecutive IDs, a column of misses.
  Framebuffer fb(16, 8, kAovPrimId);
  for (int row = 0; row < 8; ++row)
    for (int col = 0; col < 16; ++col)
      fb.primId[size_t(row) * 16 + size_t(col)] =
          col == 15 ? kInvalidId : uint32_t(col / 2 + 8 * (row / 2));
  writePreview(dir + "/prim.png", fb);
  const Png png = readPng(dir + "/prim.png");
  ASSERT_EQ(png.channels, 3);
  expectHashedIdColours(png, fb.primId);
  EXPECT_NE(png.description.find("primID"), std::string::npos) << png.description;

  // Every pair of horizontal or vertical neighbours among 4096 consecutive IDs differs.
  Framebuffer ramp(64, 64, kAovPrimId);
  for (size_t i = 0; i < ramp.pixelCount(); ++i) ramp.primId[i] = uint32_t(i);
  writePreview(dir + "/ramp.png", ramp);
  const Png r = readPng(dir + "/ramp.png");
  for (int row = 0; row < 64; ++row)
    for (int col = 0; col < 64; ++col) {
      if (col + 1 < 64) {
        EXPECT_NE(r.rgb(row, col), r.rgb(row, col + 1)) << row << "," << col;
      }
      if (row + 1 < 64) {
        EXPECT_NE(r.rgb(row, col), r.rgb(row + 1, col)) << row << "," << col;
      }
      EXPECT_NE(r.rgb(row, col), kBackground);
    }
}

TEST(Preview, GeomIdsAloneAndPrimIdsBeforeGeomIds) {
  const std::string dir = test::scratchDir();
  Framebuffer fb(4, 2, kAovGeomId);
  fb.geomId = {0, 0, 1, kInvalidId, 2, 2, 1, 0};
  writePreview(dir + "/geom.png", fb);
  const Png png = readPng(dir + "/geom.png");
  expectHashedIdColours(png, fb.geomId);
  EXPECT_NE(png.description.find("geomID"), std::string::npos) << png.description;

  // With both, the preview shows primIDs: equal geomIDs, different primIDs, different colours.
  Framebuffer both(2, 1, kAovPrimId | kAovGeomId);
  both.primId = {5, 6};
  both.geomId = {3, 3};
  EXPECT_EQ(previewAov(both.aovs), kAovPrimId);
  writePreview(dir + "/both.png", both);
  const Png b = readPng(dir + "/both.png");
  EXPECT_NE(b.rgb(0, 0), b.rgb(0, 1));
}

TEST(Preview, WhichAovIsShown) {
  EXPECT_EQ(previewAov(kAovColor | kAovDepth | kAovPrimId), kAovColor);
  EXPECT_EQ(previewAov(kAovDepth | kAovNormal | kAovPrimId), kAovDepth);
  EXPECT_EQ(previewAov(kAovNormal | kAovGeomId), kAovNormal);
  EXPECT_EQ(previewAov(kAovGeomId | kAovPosition), kAovGeomId);
  EXPECT_EQ(previewAov(kAovPosition | kAovDistance), Aov(0));
  EXPECT_EQ(previewableAovs(kAovPosition | kAovDistance), 0u);
  EXPECT_EQ(previewableAovs(kAovPosition | kAovPrimId), AovMask(kAovPrimId));
}

TEST(Preview, ErrorsNameThePath) {
  const std::string dir = test::scratchDir();
  try {
    writePreview(dir + "/p.png", Framebuffer(2, 2, kAovPosition));
    FAIL() << "no error for a framebuffer without a previewable AOV";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/p.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("position"), std::string::npos) << e.what();
  }
  try {
    writePreview(dir + "/missing/p.png", Framebuffer(2, 2, kAovColor));
    FAIL() << "no error for a missing directory";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/missing"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fileCount(dir), 0u);
}

// The one list of preview formats: the writer refuses what it lacks, and the README's and the
// batch docs' lists are it.
TEST(Preview, FormatsAreOneList) {
  const std::vector<std::string>& extensions = previewExtensions();
  EXPECT_EQ(extensions, (std::vector<std::string>{".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp",
                                                  ".tga", ".ppm"}));
  std::string list;
  for (const std::string& e : extensions) list += (list.empty() ? "" : " ") + e;
  for (const char* file : {"/../README.md", "/../docs/batch.md"}) {
    const std::string docs = test::readFile(std::string(APERTURE_TESTS_DIR) + file);
    EXPECT_NE(docs.find("`" + list + "`"), std::string::npos) << file << " lacks `" << list << "`";
  }
  const std::string batch = test::readFile(std::string(APERTURE_TESTS_DIR) + "/../docs/batch.md");
  EXPECT_NE(batch.find("showing " + previewableAovText()), std::string::npos)
      << "docs/batch.md lacks 'showing " << previewableAovText() << "'";
  EXPECT_EQ(previewableAovText(),
            "albedo, else color, depth, normal, primid, geomid, instance, mesh or material");
  const std::string dir = test::scratchDir();
  for (const char* bad : {"/p.gif", "/p.exr", "/p"}) {
    const std::string error =
        test::errorOf([&] { writePreview(dir + bad, Framebuffer(2, 2, kAovColor)); });
    EXPECT_NE(error.find("unknown preview extension"), std::string::npos) << bad << ": " << error;
    EXPECT_NE(error.find(list), std::string::npos) << error;
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
