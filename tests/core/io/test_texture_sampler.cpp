// Texture sampling through OpenImageIO (core/io/texture_sampler.h) against texel values worked
// out here: a checkerboard of distinct texels written as PNG, sampled nearest at known (s, t),
// gives its texel sRGB-decoded (IEC 61966-2-1, written out below); wraps, bilinear weights in
// linear light, embedded bytes, gray images, errors and threads.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "core/io/image_codec.h"
#include "core/io/texture_sampler.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;

namespace {

constexpr int kTexW = 4, kTexH = 2;

/// Texel (x, y) of the test image, y = 0 the top row: distinct bytes per texel and channel.
std::array<uint8_t, 3> texelBytes(int x, int y) {
  return {uint8_t(20 + 60 * x), uint8_t(200 - 90 * y), uint8_t(37 + 50 * x + 100 * y)};
}

double srgbToLinearRef(double c) {
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

glm::dvec4 texelLinear(int x, int y, bool srgb = true) {
  const auto b = texelBytes(x, y);
  glm::dvec4 out(1.0);
  for (int c = 0; c < 3; ++c)
    out[c] = srgb ? srgbToLinearRef(b[size_t(c)] / 255.0) : b[size_t(c)] / 255.0;
  return out;
}

std::vector<unsigned char> checkerPng() {
  std::vector<uint8_t> pixels;
  for (int y = 0; y < kTexH; ++y)
    for (int x = 0; x < kTexW; ++x)
      for (uint8_t v : texelBytes(x, y)) pixels.push_back(v);
  ImageToEncode image;
  image.width = kTexW, image.height = kTexH, image.channels = 3;
  image.type = SampleType::UInt8;
  image.pixels = pixels.data();
  return encodeImage("checker.png", image);
}

std::string checkerPath() {
  const std::string path = test::scratchDir() + "/texture_checker.png";
  const std::vector<unsigned char> bytes = checkerPng();
  test::writeFile(path, std::string(bytes.begin(), bytes.end()));
  return path;
}

SurfaceTexture checkerTexture(TextureWrap wrap = TextureWrap::Repeat, bool nearest = true) {
  SurfaceTexture t;
  t.where = "test.gltf: /images/0";
  t.path = checkerPath();
  t.wrapS = t.wrapT = wrap;
  t.nearest = nearest;
  return t;
}

/// The texel that holds texture coordinate c of an axis of n texels, wrapped.
int wrapTexel(double c, int n, TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::Repeat: {
      const double f = c - std::floor(c);
      return std::min(n - 1, int(std::floor(f * n)));
    }
    case TextureWrap::ClampToEdge:
      return std::clamp(int(std::floor(c * n)), 0, n - 1);
    case TextureWrap::MirroredRepeat: {
      const double period = c - 2.0 * std::floor(c / 2.0);  // [0, 2)
      const double f = period <= 1.0 ? period : 2.0 - period;
      return std::min(n - 1, int(std::floor(f * n)));
    }
  }
  return 0;
}

/// The nearest-filtered texel at (s, t), t = 0 the top row.
glm::dvec4 expectedNearest(double s, double t, TextureWrap wrap) {
  return texelLinear(wrapTexel(s, kTexW, wrap), wrapTexel(t, kTexH, wrap));
}

/// Points inside texels (away from their edges), including outside [0, 1].
std::vector<glm::dvec2> probePoints() {
  std::vector<glm::dvec2> out;
  for (int i = -6; i < 10; ++i)
    for (int j = -3; j < 5; ++j)
      out.push_back({(i + 0.3 + 0.05 * (j & 1)) / kTexW, (j + 0.6 - 0.04 * (i & 1)) / kTexH});
  return out;
}

/// How many probe points `sample(s, t)` gets wrong (beyond 1e-5) against the texel here.
template <typename F>
int mismatches(F sample, TextureWrap wrap) {
  int bad = 0;
  for (const glm::dvec2& p : probePoints()) {
    const glm::vec4 got = sample(p.x, p.y);
    const glm::dvec4 want = expectedNearest(p.x, p.y, wrap);
    for (int c = 0; c < 4; ++c)
      if (std::fabs(got[c] - want[c]) > 1e-5) {
        ++bad;
        break;
      }
  }
  return bad;
}

TEST(TextureSampler, NearestGivesTheTexelSrgbDecoded) {
  for (TextureWrap wrap :
       {TextureWrap::Repeat, TextureWrap::ClampToEdge, TextureWrap::MirroredRepeat}) {
    const auto sampler = openTextureSampler({checkerTexture(wrap)});
    EXPECT_EQ(mismatches([&](double s, double t) { return sampler->sample(0, float(s), float(t)); },
                         wrap),
              0)
        << "wrap " << int(wrap);
  }
}

// The comparison above catches a texture read upside down (t -> 1 - t: OBJ's vt convention
// unconverted) and one read with the wrong wrap.
TEST(TextureSampler, TheComparisonCatchesAFlippedVAndAWrongWrap) {
  const auto sampler = openTextureSampler({checkerTexture(TextureWrap::Repeat)});
  EXPECT_GT(
      mismatches([&](double s, double t) { return sampler->sample(0, float(s), float(1 - t)); },
                 TextureWrap::Repeat),
      20);
  EXPECT_GT(mismatches([&](double s, double t) { return sampler->sample(0, float(s), float(t)); },
                       TextureWrap::ClampToEdge),
            20);
}

void expectTexel(const glm::vec4& got, const glm::dvec4& want, const char* what) {
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(got[c], want[c], 1e-6) << what << ", channel " << c;
}

TEST(TextureSampler, WrapsDifferOutsideTheUnitSquare) {
  const auto repeat = openTextureSampler({checkerTexture(TextureWrap::Repeat)});
  const auto clamp = openTextureSampler({checkerTexture(TextureWrap::ClampToEdge)});
  const auto mirror = openTextureSampler({checkerTexture(TextureWrap::MirroredRepeat)});
  const float t = 0.25f;  // row 0
  // s = 1.1: repeat reads column 0 (0.1), clamp column 3 (the edge), mirror column 3 (0.9).
  expectTexel(repeat->sample(0, 1.1f, t), texelLinear(0, 0), "repeat at s = 1.1");
  expectTexel(clamp->sample(0, 1.1f, t), texelLinear(3, 0), "clamp at s = 1.1");
  expectTexel(mirror->sample(0, 1.1f, t), texelLinear(3, 0), "mirror at s = 1.1");
  // s = 1.4: repeat column 1, clamp column 3, mirror column 2 (0.6).
  expectTexel(repeat->sample(0, 1.4f, t), texelLinear(1, 0), "repeat at s = 1.4");
  expectTexel(clamp->sample(0, 1.4f, t), texelLinear(3, 0), "clamp at s = 1.4");
  expectTexel(mirror->sample(0, 1.4f, t), texelLinear(2, 0), "mirror at s = 1.4");
  // Within [0, 1] they agree.
  EXPECT_EQ(glm::dvec4(repeat->sample(0, 0.6f, 0.7f)), glm::dvec4(clamp->sample(0, 0.6f, 0.7f)));
  EXPECT_EQ(glm::dvec4(repeat->sample(0, 0.6f, 0.7f)), glm::dvec4(mirror->sample(0, 0.6f, 0.7f)));
}

// Bilinear weights act on linear values (sRGB decoded before filtering): halfway between the
// centres of texels (1, 0) and (2, 0) the sample is their linear mean, which differs from the
// decoded mean of the encoded values.
TEST(TextureSampler, BilinearFiltersLinearValues) {
  const auto sampler = openTextureSampler({checkerTexture(TextureWrap::ClampToEdge, false)});
  const float s = 2.0f / kTexW, t = 0.5f / kTexH;  // between columns 1 and 2, row 0's centre
  const glm::vec4 got = sampler->sample(0, s, t);
  const glm::dvec4 want = 0.5 * (texelLinear(1, 0) + texelLinear(2, 0));
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(got[c], want[c], 1e-5) << c;
  const auto a = texelBytes(1, 0), b = texelBytes(2, 0);
  const double encodedMean = srgbToLinearRef((a[0] + b[0]) / 510.0);
  EXPECT_GT(std::fabs(got[0] - encodedMean), 1e-3);
  // A quarter of the way: weights 0.75, 0.25.
  const glm::vec4 quarter = sampler->sample(0, 1.75f / kTexW, t);
  const glm::dvec4 wantQuarter = 0.75 * texelLinear(1, 0) + 0.25 * texelLinear(2, 0);
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(quarter[c], wantQuarter[c], 1e-5) << c;
}

TEST(TextureSampler, EmbeddedBytesAndLinearTextures) {
  SurfaceTexture embedded = checkerTexture();
  embedded.path.clear();
  embedded.bytes = checkerPng();
  embedded.mimeType = "image/png";
  SurfaceTexture linear = checkerTexture();
  linear.srgb = false;
  const auto sampler = openTextureSampler({checkerTexture(), embedded, linear});
  for (const glm::dvec2& p : probePoints()) {
    EXPECT_EQ(glm::dvec4(sampler->sample(1, float(p.x), float(p.y))),
              glm::dvec4(sampler->sample(0, float(p.x), float(p.y))));
    const int x = wrapTexel(p.x, kTexW, TextureWrap::Repeat),
              y = wrapTexel(p.y, kTexH, TextureWrap::Repeat);
    const glm::vec4 raw = sampler->sample(2, float(p.x), float(p.y));
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(raw[c], texelLinear(x, y, false)[c], 1e-6);
  }
  EXPECT_EQ(glm::dvec4(sampler->sample(3, 0.5f, 0.5f)), glm::dvec4(0.0)) << "out of range";
}

TEST(TextureSampler, GrayAlphaWidensToRgba) {
  const uint8_t pixels[4] = {255, 51, 0, 255};  // (gray, alpha) x 2
  ImageToEncode image;
  image.width = 2, image.height = 1, image.channels = 2;
  image.pixels = pixels;
  SurfaceTexture t;
  t.where = "gray";
  t.bytes = encodeImage("g.png", image);
  t.mimeType = "image/png";
  t.nearest = true;
  const auto sampler = openTextureSampler({t});
  expectTexel(sampler->sample(0, 0.25f, 0.5f), glm::dvec4(1, 1, 1, 51 / 255.0), "white, alpha 0.2");
  expectTexel(sampler->sample(0, 0.75f, 0.5f), glm::dvec4(0, 0, 0, 1), "black, opaque");
}

TEST(TextureSampler, MissingOrUndecodableTexturesNameWhereTheyAre) {
  SurfaceTexture missing = checkerTexture();
  missing.where = "room.mtl:7";
  missing.path = test::scratchDir() + "/no_such_texture.png";
  std::string error = test::errorOf([&] { openTextureSampler({checkerTexture(), missing}); });
  EXPECT_NE(error.find("room.mtl:7"), std::string::npos) << error;
  EXPECT_NE(error.find("no_such_texture.png"), std::string::npos) << error;
  SurfaceTexture garbage;
  garbage.where = "scene.glb: /images/2";
  garbage.bytes = {'n', 'o', 't', ' ', 'a', 'n', ' ', 'i', 'm', 'a', 'g', 'e'};
  garbage.mimeType = "image/png";
  error = test::errorOf([&] { openTextureSampler({garbage}); });
  EXPECT_NE(error.find("scene.glb: /images/2"), std::string::npos) << error;
  EXPECT_NE(error.find("embedded"), std::string::npos) << error;
}

TEST(TextureSampler, SafeFromManyThreads) {
  const auto sampler = openTextureSampler({checkerTexture(TextureWrap::MirroredRepeat)});
  std::vector<int> bad(4, -1);
  std::vector<std::thread> threads;
  for (size_t k = 0; k < bad.size(); ++k)
    threads.emplace_back([&, k] {
      int sum = 0;
      for (int round = 0; round < 50; ++round)
        sum +=
            mismatches([&](double s, double t) { return sampler->sample(0, float(s), float(t)); },
                       TextureWrap::MirroredRepeat);
      bad[k] = sum;
    });
  for (std::thread& t : threads) t.join();
  for (int b : bad) EXPECT_EQ(b, 0);
}

}  // namespace
