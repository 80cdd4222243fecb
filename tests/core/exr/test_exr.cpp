// EXR output/input (the atomic writes under it: tests/core/io/test_atomic_file.cpp).
#include <Imath/ImathBox.h>
#include <Imath/ImathMatrix.h>
#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfMatrixAttribute.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfStringVectorAttribute.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/glm.hpp>
#include <map>

#include "core/exr/exr.h"
#include "core/util/error.h"
#include "tests/exr_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::kAllAovs;
using test::patterned;
using test::readBytes;

/// Reads one channel of `path` with OpenEXR directly (not through readExr).
template <typename T>
std::vector<T> readChannel(Imf::InputFile& file, const char* name, Imf::PixelType as) {
  const Imath::Box2i dw = file.header().dataWindow();
  const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
  std::vector<T> out(size_t(w) * size_t(h));
  Imf::FrameBuffer frame;
  frame.insert(name, Imf::Slice::Make(as, out.data(), dw, sizeof(T)));
  file.setFrameBuffer(frame);
  file.readPixels(dw.min.y, dw.max.y);
  return out;
}

void expectFloatsEqual(const std::vector<float>& got, const std::vector<float>& want,
                       const char* what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  for (size_t i = 0; i < got.size(); ++i)
    ASSERT_EQ(std::memcmp(&got[i], &want[i], sizeof(float)), 0)
        << what << "[" << i << "]: " << got[i] << " vs " << want[i];
}

std::vector<float> component(const std::vector<float>& v, int c, int n) {
  std::vector<float> out;
  for (size_t i = c; i < v.size(); i += size_t(n)) out.push_back(v[i]);
  return out;
}

void checkDirectRead(const std::string& path, const Framebuffer& fb, bool halfColor) {
  Imf::InputFile file(path.c_str());
  std::map<std::string, Imf::PixelType> channels;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
    channels[it.name()] = it.channel().type;
  const Imf::PixelType colorType = halfColor ? Imf::HALF : Imf::FLOAT;
  const std::map<std::string, Imf::PixelType> expected = {
      {"R", colorType},      {"G", colorType},     {"B", colorType},    {"A", colorType},
      {"Z", Imf::FLOAT},     {"T", Imf::FLOAT},    {"N.X", Imf::FLOAT}, {"N.Y", Imf::FLOAT},
      {"N.Z", Imf::FLOAT},   {"P.X", Imf::FLOAT},  {"P.Y", Imf::FLOAT}, {"P.Z", Imf::FLOAT},
      {"primID", Imf::UINT}, {"geomID", Imf::UINT}};
  EXPECT_EQ(channels, expected);
  const Imath::Box2i dw = file.header().dataWindow();
  EXPECT_EQ(dw.max.x - dw.min.x + 1, fb.width);
  EXPECT_EQ(dw.max.y - dw.min.y + 1, fb.height);

  const char* rgba[4] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c) {
    const std::vector<float> got = readChannel<float>(file, rgba[c], Imf::FLOAT);
    const std::vector<float> want = component(fb.rgba, c, 4);
    if (!halfColor) {
      expectFloatsEqual(got, want, rgba[c]);
    } else {
      ASSERT_EQ(got.size(), want.size());
      for (size_t i = 0; i < got.size(); ++i)  // half: 11 significant bits, round to nearest
        ASSERT_NEAR(got[i], want[i], std::abs(want[i]) * std::ldexp(1.0, -11) + 1e-7)
            << rgba[c] << "[" << i << "]";
    }
  }
  expectFloatsEqual(readChannel<float>(file, "Z", Imf::FLOAT), fb.depth, "Z");
  expectFloatsEqual(readChannel<float>(file, "T", Imf::FLOAT), fb.distance, "T");
  const char* n[3] = {"N.X", "N.Y", "N.Z"};
  const char* p[3] = {"P.X", "P.Y", "P.Z"};
  for (int c = 0; c < 3; ++c) {
    expectFloatsEqual(readChannel<float>(file, n[c], Imf::FLOAT), component(fb.normal, c, 3), n[c]);
    expectFloatsEqual(readChannel<float>(file, p[c], Imf::FLOAT), component(fb.position, c, 3),
                      p[c]);
  }
  EXPECT_EQ(readChannel<uint32_t>(file, "primID", Imf::UINT), fb.primId);
  EXPECT_EQ(readChannel<uint32_t>(file, "geomID", Imf::UINT), fb.geomId);
}

TEST(Exr, RoundTripFloatThroughOpenExr) {
  const std::string path = test::scratchDir() + "/all.exr";
  const Framebuffer fb = patterned(13, 7);
  writeExr(path, fb, ExrMetadata{});
  checkDirectRead(path, fb, false);
}

TEST(Exr, StringVectorsAreOpenExrStringVectorAttributes) {
  const std::string path = test::scratchDir() + "/names.exr";
  ExrMetadata meta;
  const std::vector<std::string> nodes = {"chair_1", "", "table;legs", "n\u00e9"};
  meta.stringVectors = {{"aperture.meshNames", {"m"}}, {"aperture.instanceNames", nodes}};
  writeExr(path, patterned(5, 3), meta);
  Imf::InputFile file(path.c_str());
  const auto* stored =
      file.header().findTypedAttribute<Imf::StringVectorAttribute>("aperture.instanceNames");
  ASSERT_NE(stored, nullptr);
  EXPECT_EQ(stored->value(), nodes);
  ExrMetadata back;
  readExr(path, &back);
  ASSERT_EQ(back.stringVectors.size(), 2u);  // sorted by name
  EXPECT_EQ(back.stringVectors[0].first, "aperture.instanceNames");
  EXPECT_EQ(back.stringVectors[0].second, nodes);
  EXPECT_EQ(back.stringVectors[1].second, std::vector<std::string>{"m"});
}

TEST(Exr, RoundTripHalfColorThroughOpenExr) {
  const std::string path = test::scratchDir() + "/half.exr";
  const Framebuffer fb = patterned(9, 11);
  ExrOptions options;
  options.halfColor = true;
  writeExr(path, fb, ExrMetadata{}, options);
  checkDirectRead(path, fb, true);
}

TEST(Exr, ReadExrRestoresEveryAov) {
  const std::string path = test::scratchDir() + "/all.exr";
  const Framebuffer fb = patterned(10, 6);
  writeExr(path, fb, ExrMetadata{});
  const Framebuffer back = readExr(path);
  EXPECT_EQ(back.width, fb.width);
  EXPECT_EQ(back.height, fb.height);
  EXPECT_EQ(back.aovs, kAllAovs);
  expectFloatsEqual(back.rgba, fb.rgba, "rgba");
  expectFloatsEqual(back.depth, fb.depth, "depth");
  expectFloatsEqual(back.distance, fb.distance, "distance");
  expectFloatsEqual(back.normal, fb.normal, "normal");
  expectFloatsEqual(back.position, fb.position, "position");
  EXPECT_EQ(back.primId, fb.primId);
  EXPECT_EQ(back.geomId, fb.geomId);
}

TEST(Exr, OnlyRequestedAovsAreWritten) {
  const std::string path = test::scratchDir() + "/some.exr";
  Framebuffer fb(4, 3, kAovDepth | kAovGeomId);
  fb.depth[5] = 2.5f;
  fb.geomId[2] = 9;
  writeExr(path, fb, ExrMetadata{});
  Imf::InputFile file(path.c_str());
  std::vector<std::string> names;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
    names.push_back(it.name());
  EXPECT_EQ(names, (std::vector<std::string>{"Z", "geomID"}));
  const Framebuffer back = readExr(path);
  EXPECT_EQ(back.aovs, kAovDepth | kAovGeomId);
  EXPECT_EQ(back.depth[5], 2.5f);
  EXPECT_EQ(back.geomId[2], 9u);
  EXPECT_TRUE(back.rgba.empty());
}

TEST(Exr, CompressionNamesParse) {
  const char* names[] = {"none",  "rle", "zips", "zip",  "piz",
                         "pxr24", "b44", "b44a", "dwaa", "dwab"};
  for (const char* name : names) EXPECT_EQ(exrCompressionName(parseExrCompression(name)), name);
  try {
    parseExrCompression("lzw");
    FAIL() << "no error for an unknown compression";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("lzw"), std::string::npos) << what;
    EXPECT_NE(what.find("piz"), std::string::npos) << what;
    EXPECT_NE(what.find("dwab"), std::string::npos) << what;
  }
}

TEST(Exr, EveryCompressionWritesAReadableFile) {
  const std::string dir = test::scratchDir();
  const Framebuffer fb = patterned(40, 37);  // several scanline blocks for every compression
  const std::string lossless[] = {"none", "rle", "zips", "zip", "piz"};
  for (const char* name :
       {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"}) {
    SCOPED_TRACE(name);
    for (bool halfColor : {false, true}) {
      SCOPED_TRACE(halfColor ? "half color" : "float color");
      const std::string path = dir + "/" + name + (halfColor ? "-half" : "") + ".exr";
      ExrOptions options;
      options.compression = parseExrCompression(name);
      options.halfColor = halfColor;
      writeExr(path, fb, ExrMetadata{}, options);
      EXPECT_TRUE(isCompleteExr(path));
      const Framebuffer back = readExr(path);
      // Integer channels are lossless under every compression.
      EXPECT_EQ(back.primId, fb.primId);
      EXPECT_EQ(back.geomId, fb.geomId);
      const bool exact = std::find(std::begin(lossless), std::end(lossless), std::string(name)) !=
                         std::end(lossless);
      if (exact) {
        expectFloatsEqual(back.depth, fb.depth, "depth");
        expectFloatsEqual(back.distance, fb.distance, "distance");
        expectFloatsEqual(back.normal, fb.normal, "normal");
        expectFloatsEqual(back.position, fb.position, "position");
        if (!halfColor) expectFloatsEqual(back.rgba, fb.rgba, "rgba");
      } else {
        // Lossy: DWA also quantises FLOAT channels named like CIE XYZ (Z, N.X, P.Y, ...).
        for (size_t i = 0; i < fb.depth.size(); ++i) {
          if (std::isinf(fb.depth[i])) {
            EXPECT_EQ(back.depth[i], fb.depth[i]);
          } else {
            EXPECT_NEAR(back.depth[i], fb.depth[i], 2e-2 * fb.depth[i]) << i;
          }
        }
        for (size_t i = 0; i < fb.position.size(); ++i)
          EXPECT_NEAR(back.position[i], fb.position[i], 2e-2 * (1 + std::abs(fb.position[i])));
        for (size_t i = 0; i < fb.rgba.size(); ++i)
          EXPECT_NEAR(back.rgba[i], fb.rgba[i], 0.1 * (1 + fb.rgba[i])) << i;
      }
    }
  }
}

TEST(Exr, FileBytesDoNotDependOnOpenExrThreads) {
  // OpenEXR's pool (exrThreads) encodes chunks in parallel and writes them in line order: the
  // file is the one the writer's thread alone makes. Every compression, lossy ones included.
  const std::string dir = test::scratchDir();
  const Framebuffer fb = patterned(96, 80);  // several chunks for every compression
  for (const char* name :
       {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"}) {
    SCOPED_TRACE(name);
    ExrOptions options;
    options.compression = parseExrCompression(name);
    const std::string alone = dir + "/" + name + "-alone.exr", pooled = dir + "/" + name + ".exr";
    {
      const ExrEncodingThreads none(1, ExrCompression::Zip);
      ASSERT_EQ(exrThreads(), 0);
      writeExr(alone, fb, ExrMetadata{}, options);
    }
    {
      const ExrEncodingThreads three(3, ExrCompression::Zip);
      ASSERT_EQ(exrThreads(), 3);
      writeExr(pooled, fb, ExrMetadata{}, options);
    }
    const std::string bytes = readBytes(alone);
    EXPECT_FALSE(bytes.empty());
    EXPECT_TRUE(bytes == readBytes(pooled));
  }
}

TEST(Exr, EncodingThreadsGoOnlyToFilesThatEncode) {
  const int before = exrThreads();
  {
    const ExrEncodingThreads zip(3, ExrCompression::Zip);
    EXPECT_EQ(exrThreads(), 3);
    {
      // An uncompressed file: the pool would only pass its scanlines to other threads.
      const ExrEncodingThreads none(3, ExrCompression::None);
      EXPECT_EQ(exrThreads(), 0);
    }
    EXPECT_EQ(exrThreads(), 3);
    {
      // One thread: the writer's own.
      const ExrEncodingThreads one(1, ExrCompression::Piz);
      EXPECT_EQ(exrThreads(), 0);
    }
    EXPECT_EQ(exrThreads(), 3);
  }
  EXPECT_EQ(exrThreads(), before);
}

TEST(Exr, CompressionIsRecordedInTheHeader) {
  const std::string dir = test::scratchDir();
  const Framebuffer fb = patterned(8, 8);
  const std::pair<const char*, Imf::Compression> cases[] = {{"none", Imf::NO_COMPRESSION},
                                                            {"piz", Imf::PIZ_COMPRESSION},
                                                            {"dwab", Imf::DWAB_COMPRESSION}};
  for (const auto& [name, imf] : cases) {
    ExrOptions options;
    options.compression = parseExrCompression(name);
    writeExr(dir + "/c.exr", fb, ExrMetadata{}, options);
    Imf::InputFile file((dir + "/c.exr").c_str());
    EXPECT_EQ(file.header().compression(), imf) << name;
  }
}

glm::dmat4 testMatrix(double seed) {
  glm::dmat4 m;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] = seed + 0.1 * c - 0.37 * r + 1e-9 * (4 * c + r);
  return m;
}

TEST(Exr, HeaderMetadataRoundTrip) {
  const std::string path = test::scratchDir() + "/meta.exr";
  ExrMetadata meta;
  CameraDescription& cam = meta.camera;
  cam.type = "thinlens";
  cam.eye = {1.5, -2.25, 3.1234567890123};
  cam.u = {0.6, 0.8, 0};
  cam.v = {0, 0, 1};
  cam.w = {0.8, -0.6, 0};
  cam.d = 0.7654321;
  cam.vw = 1.25;
  cam.vh = 0.8;
  cam.width = 6;
  cam.height = 4;
  cam.spp = 17;
  cam.exrCameraFromWorld = testMatrix(0.3);
  cam.ndcFromWorld = testMatrix(-1.7);
  cam.pixelAspectRatio = 0.8125;  // exact in float, like the screen window below
  cam.screenWindowCenter = {0.25, -0.375};
  cam.screenWindowWidth = 1.5;
  cam.extra = {{"fov", "60"}, {"aperture", "0.05"}};
  meta.renderSeconds = 12.375;
  meta.strings = {{"aperture.mesh", "bunny.obj"}, {"aperture.settings", "{\"x\": 1}"}};
  writeExr(path, Framebuffer(6, 4, kAovColor), meta);

  ExrMetadata back;
  readExr(path, &back);
  EXPECT_EQ(back.camera.type, cam.type);
  EXPECT_EQ(back.camera.eye, cam.eye);
  EXPECT_EQ(back.camera.u, cam.u);
  EXPECT_EQ(back.camera.v, cam.v);
  EXPECT_EQ(back.camera.w, cam.w);
  EXPECT_EQ(back.camera.d, cam.d);
  EXPECT_EQ(back.camera.vw, cam.vw);
  EXPECT_EQ(back.camera.vh, cam.vh);
  EXPECT_EQ(back.camera.width, 6);
  EXPECT_EQ(back.camera.height, 4);
  EXPECT_EQ(back.camera.spp, 17);
  EXPECT_EQ(back.camera.exrCameraFromWorld, cam.exrCameraFromWorld);
  EXPECT_EQ(back.camera.ndcFromWorld, cam.ndcFromWorld);
  EXPECT_EQ(back.camera.pixelAspectRatio, cam.pixelAspectRatio);
  EXPECT_EQ(back.camera.screenWindowCenter, cam.screenWindowCenter);
  EXPECT_EQ(back.camera.screenWindowWidth, cam.screenWindowWidth);
  EXPECT_FALSE(back.camera.equirect.has_value());
  EXPECT_FALSE(back.camera.fisheye.has_value());
  // Header attributes are kept sorted by name, so the pairs come back in name order.
  auto sorted = [](std::vector<std::pair<std::string, std::string>> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_EQ(back.camera.extra, sorted(cam.extra));
  EXPECT_EQ(back.renderSeconds, 12.375);
  EXPECT_EQ(back.strings, sorted(meta.strings));

  // The same values as OpenEXR sees them: standard float matrices and named attributes.
  Imf::InputFile file(path.c_str());
  const Imf::Header& h = file.header();
  ASSERT_TRUE(Imf::hasWorldToCamera(h));
  ASSERT_TRUE(Imf::hasWorldToNDC(h));
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      EXPECT_EQ(Imf::worldToCamera(h)[i][j], float(cam.exrCameraFromWorld[i][j]));
      EXPECT_EQ(Imf::worldToNDC(h)[i][j], float((*cam.ndcFromWorld)[i][j]));
    }
  EXPECT_EQ(h.pixelAspectRatio(), 0.8125f);
  EXPECT_EQ(h.screenWindowCenter(), Imath::V2f(0.25f, -0.375f));
  EXPECT_EQ(h.screenWindowWidth(), 1.5f);
  const auto* fov = h.findTypedAttribute<Imf::StringAttribute>("aperture.camera.fov");
  ASSERT_NE(fov, nullptr);
  EXPECT_EQ(fov->value(), "60");
  const auto* software = h.findTypedAttribute<Imf::StringAttribute>("software");
  ASSERT_NE(software, nullptr);
  EXPECT_EQ(software->value(), "aperture " APERTURE_VERSION);
  EXPECT_NE(h.findTypedAttribute<Imf::M44dAttribute>("aperture.worldToNDC"), nullptr);
}

TEST(Exr, PanoramaProjectionRoundTripsWithoutWorldToNdc) {
  const std::string dir = test::scratchDir();
  ExrMetadata equirect;
  equirect.camera.type = "equirect";
  equirect.camera.equirect = EquirectProjection{{-150.5, 170.25}, {-70, 40.125}};
  equirect.camera.pixelAspectRatio = 1.25;
  writeExr(dir + "/e.exr", Framebuffer(8, 4, kAovDepth), equirect);
  ExrMetadata fisheye;
  fisheye.camera.type = "fisheye";
  fisheye.camera.fisheye = FisheyeProjection{200.5, {4.0, 2.5}, 2.0};
  writeExr(dir + "/f.exr", Framebuffer(8, 5, kAovDepth), fisheye);

  ExrMetadata back;
  readExr(dir + "/e.exr", &back);
  EXPECT_FALSE(back.camera.ndcFromWorld.has_value());
  ASSERT_TRUE(back.camera.equirect.has_value());
  EXPECT_EQ(back.camera.equirect->longitudeDeg, glm::dvec2(-150.5, 170.25));
  EXPECT_EQ(back.camera.equirect->latitudeDeg, glm::dvec2(-70, 40.125));
  EXPECT_EQ(back.camera.pixelAspectRatio, 1.25);
  EXPECT_FALSE(back.camera.fisheye.has_value());
  readExr(dir + "/f.exr", &back);
  EXPECT_FALSE(back.camera.ndcFromWorld.has_value());
  ASSERT_TRUE(back.camera.fisheye.has_value());
  EXPECT_EQ(back.camera.fisheye->fovDeg, 200.5);
  EXPECT_EQ(back.camera.fisheye->centerPx, glm::dvec2(4.0, 2.5));
  EXPECT_EQ(back.camera.fisheye->radiusPx, 2.0);
  EXPECT_EQ(back.strings.size(), 0u);  // aperture.fisheye.mapping is not returned as a string

  for (const char* file : {"/e.exr", "/f.exr"}) {
    Imf::InputFile in((dir + file).c_str());
    EXPECT_FALSE(Imf::hasWorldToNDC(in.header())) << file;
    EXPECT_EQ(in.header().findTypedAttribute<Imf::M44dAttribute>("aperture.worldToNDC"), nullptr);
    EXPECT_TRUE(Imf::hasWorldToCamera(in.header())) << file;
  }
}

TEST(Exr, PixelAspectRatioOutsideOpenExrsRangeIsAnErrorNamingTheFile) {
  const std::string path = test::scratchDir() + "/thin.exr";
  ExrMetadata meta;
  meta.camera.pixelAspectRatio = 2e6;
  try {
    writeExr(path, Framebuffer(4, 4, kAovDepth), meta);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("thin.exr"), std::string::npos) << e.what();
    EXPECT_NE(
        std::string(e.what()).find("pixel aspect ratio 2000000 (viewport 1x1 over 4x4 pixels)"),
        std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(test::fileExists(path));
}

/// A pinhole camera built by hand: looks from `eye` at `target`, image plane at distance d with
/// a vw x vh viewport, W x H pixels. NDC x = column / W, y = row / H (top-left origin).
struct HandCamera {
  glm::dvec3 eye, u, v, w;
  double d, vw, vh;
  int width, height;

  CameraDescription describe() const {
    CameraDescription c;
    c.type = "perspective";
    c.eye = eye;
    c.u = u;
    c.v = v;
    c.w = w;
    c.d = d;
    c.vw = vw;
    c.vh = vh;
    c.width = width;
    c.height = height;
    c.exrCameraFromWorld = exrCameraFromFrame(eye, u, v, w);  // z = depth along −W
    // Camera space (x, y, z) -> homogeneous (d x / vw + 0.5 z, -d y / vh + 0.5 z, 1, z).
    glm::dmat4 projection(0.0);
    projection[0][0] = d / vw;
    projection[2][0] = 0.5;
    projection[1][1] = -d / vh;
    projection[2][1] = 0.5;
    projection[3][2] = 1.0;
    projection[2][3] = 1.0;
    c.ndcFromWorld = projection * c.exrCameraFromWorld;
    return c;
  }

  /// The pixel `p` projects to by similar triangles (no matrices); false if off-image.
  bool pixelOf(const glm::dvec3& p, int* row, int* col) const {
    const glm::dvec3 q = p - eye;
    const double x = glm::dot(q, u), y = glm::dot(q, v), z = glm::dot(q, w);
    if (z >= 0) return false;
    const double planeX = d * x / -z, planeY = d * y / -z;
    const double ndcX = (planeX + vw / 2) / vw, ndcY = (vh / 2 - planeY) / vh;
    *col = int(std::floor(ndcX * width));
    *row = int(std::floor(ndcY * height));
    return *col >= 0 && *col < width && *row >= 0 && *row < height;
  }
};

TEST(Exr, WorldToNdcReprojectsPositionsIntoTheirPixels) {
  HandCamera cam;
  cam.eye = {2.0, 1.0, 5.0};
  const glm::dvec3 target{0.2, -0.3, 0.1}, up{0, 1, 0};
  cam.w = glm::normalize(cam.eye - target);
  cam.u = glm::normalize(glm::cross(up, cam.w));
  cam.v = glm::cross(cam.w, cam.u);
  cam.d = 1.3;
  cam.vw = 1.6;
  cam.vh = 0.9;
  cam.width = 32;
  cam.height = 18;

  // Known points spread through the view volume, each stored at the pixel it projects to.
  Framebuffer fb(cam.width, cam.height, kAovPosition | kAovPrimId);
  std::vector<std::pair<int, int>> filled;
  for (int k = 0; k < 400; ++k) {
    const glm::dvec3 p = target + glm::dvec3(std::sin(1.3 * k) * 2.0, std::cos(0.7 * k) * 1.1,
                                             std::sin(0.31 * k + 1.0) * 1.5);
    int row, col;
    if (!cam.pixelOf(p, &row, &col)) continue;
    const size_t i = size_t(row) * cam.width + col;
    for (int c = 0; c < 3; ++c) fb.position[3 * i + c] = float(p[c]);
    fb.primId[i] = uint32_t(k);
    filled.emplace_back(row, col);
  }
  ASSERT_GT(filled.size(), 50u);
  ExrMetadata meta;
  meta.camera = cam.describe();
  const std::string path = test::scratchDir() + "/reproject.exr";
  writeExr(path, fb, meta);

  Imf::InputFile file(path.c_str());
  const Imath::M44f m = Imf::worldToNDC(file.header());
  const Framebuffer back = readExr(path);
  int checked = 0;
  for (int row = 0; row < cam.height; ++row)
    for (int col = 0; col < cam.width; ++col) {
      const size_t i = size_t(row) * cam.width + col;
      if (back.primId[i] == kInvalidId) continue;
      // Imath row-vector convention: [x y z 1] * M, then divide by w.
      const float p[4] = {back.position[3 * i], back.position[3 * i + 1], back.position[3 * i + 2],
                          1.0f};
      double h[4] = {0, 0, 0, 0};
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 4; ++k) h[j] += double(p[k]) * m[k][j];
      const double ndcX = h[0] / h[3], ndcY = h[1] / h[3];
      EXPECT_EQ(int(std::floor(ndcX * cam.width)), col) << "row " << row << " ndc " << ndcX;
      EXPECT_EQ(int(std::floor(ndcY * cam.height)), row) << "col " << col << " ndc " << ndcY;
      ++checked;
    }
  EXPECT_GT(checked, 50);
}

TEST(Exr, IsCompleteExrDetectsDamage) {
  const std::string dir = test::scratchDir();
  const std::string good = dir + "/good.exr";
  ExrOptions options;
  options.compression = ExrCompression::None;
  writeExr(good, patterned(64, 64), ExrMetadata{}, options);
  EXPECT_TRUE(isCompleteExr(good));

  const std::string bytes = readBytes(good);
  test::writeFile(dir + "/half.exr", bytes.substr(0, bytes.size() / 2));
  EXPECT_FALSE(isCompleteExr(dir + "/half.exr"));
  test::writeFile(dir + "/nearly.exr", bytes.substr(0, bytes.size() - 1));
  EXPECT_FALSE(isCompleteExr(dir + "/nearly.exr"));
  test::writeFile(dir + "/empty.exr", "");
  EXPECT_FALSE(isCompleteExr(dir + "/empty.exr"));
  test::writeFile(dir + "/text.exr", "this is not an OpenEXR file\n");
  EXPECT_FALSE(isCompleteExr(dir + "/text.exr"));
  EXPECT_FALSE(isCompleteExr(dir + "/missing.exr"));

  try {
    readExr(dir + "/half.exr");
    FAIL() << "no error reading a truncated file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("half.exr"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace aperture
