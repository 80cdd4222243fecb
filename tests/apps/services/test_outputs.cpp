// Output paths checked before any work (apps/services/outputs.h), every preview extension
// written, and the depth range a batch's previews share. The order of a view's files:
// test_view.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "apps/services/outputs.h"
#include "core/exr/exr.h"
#include "core/io/image.h"
#include "core/util/error.h"
#include "tests/support.h"
#include "tests/unwritable_dir.h"

using namespace aperture;
using namespace aperture::app;
namespace fs = std::filesystem;

namespace {

using aperture::test::errorOf;

/// Every file under `dir`, recursively (relative names).
std::vector<std::string> filesUnder(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (!e.is_directory()) names.push_back(fs::relative(e.path(), dir).string());
  return names;
}

TEST(Outputs, NamesAreCheckedForTheirRole) {
  const std::string dir = test::scratchDir();
  fs::create_directories(dir + "/adir.exr");
  struct Case {
    std::string name, path;
    OutputKind kind;
    std::string expect;
  } refused[] = {
      {"--out", dir + "/x.png", OutputKind::Exr, "unknown extension '.png'; supported: .exr"},
      {"--out", dir + "/x", OutputKind::Exr, "has no extension; supported: .exr"},
      {"--out", dir + "/adir.exr", OutputKind::Exr, "is a directory"},
      {"--out", dir, OutputKind::Exr, "is a directory"},
      {"--out", dir + "/new/", OutputKind::Exr, "is a directory name"},
      {"--preview", dir, OutputKind::Preview, "is a directory"},
      {"--preview", dir + "/p.exr", OutputKind::Preview,
       "unknown extension '.exr'; supported: .png"},
      {"--preview", dir + "/p.gif", OutputKind::Preview, ".png .jpg .jpeg .tif .tiff .bmp"},
      {"output", "out/{camera}.png", OutputKind::Exr, "unknown extension '.png'"},
  };
  for (const Case& c : refused) {
    const std::string message = errorOf([&] { checkOutputName(c.name, c.path, c.kind); });
    EXPECT_EQ(message.rfind(c.name + ": '" + c.path + "': ", 0), 0u) << message;
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.path << ": " << message;
  }
  // "is a directory" is what a directory gets, not "unknown extension ''".
  EXPECT_EQ(errorOf([&] { checkOutputName("--out", dir, OutputKind::Exr); }).find("extension"),
            std::string::npos);
  for (const char* ok : {"x.exr", "x.EXR", "out/{camera}_{frame:04d}.exr"})
    EXPECT_EQ(errorOf([&] { checkOutputName("--out", ok, OutputKind::Exr); }), "") << ok;
  for (const std::string& ext : supportedExtensions(OutputKind::Preview))
    EXPECT_EQ(errorOf([&] { checkOutputName("--preview", "p" + ext, OutputKind::Preview); }), "");
  EXPECT_EQ(filesUnder(dir).size(), 0u);
}

TEST(Outputs, DirectoriesMustExistOrBeCreatableAndWritable) {
  const std::string dir = test::scratchDir();
  test::writeFile(dir + "/afile", "a regular file");
  // Missing directories that can be created are fine (they are created when writing).
  EXPECT_EQ(errorOf([&] { checkOutputPath("--out", dir + "/new/sub/x.exr", OutputKind::Exr); }),
            "");
  EXPECT_EQ(errorOf([&] { checkOutputPath("--out", "x.exr", OutputKind::Exr); }), "");
  const std::string blocked = dir + "/afile/sub/x.exr";
  std::string message = errorOf([&] { checkOutputPath("--out", blocked, OutputKind::Exr); });
  EXPECT_NE(message.find("--out: '" + blocked + "': cannot create directory '" + dir +
                         "/afile/sub': '" + dir + "/afile' is not a directory"),
            std::string::npos)
      << message;
  EXPECT_FALSE(fs::exists(dir + "/new")) << "checking creates nothing";

  APERTURE_REQUIRE_UNWRITABLE_DIR(ro, dir + "/ro");
  message =
      errorOf([&] { checkOutputPath("--preview", ro.path() + "/p.png", OutputKind::Preview); });
  EXPECT_NE(message.find("--preview: '" + ro.path() + "/p.png': directory '" + ro.path() +
                         "' is not writable"),
            std::string::npos)
      << message;
  message = errorOf([&] { checkOutputPath("--out", ro.path() + "/a/b/x.exr", OutputKind::Exr); });
  EXPECT_NE(message.find("cannot create directory '" + ro.path() + "/a/b' in '" + ro.path() + "'"),
            std::string::npos)
      << message;
}

TEST(Outputs, PreviewRangesAndPreviewableAovs) {
  EXPECT_EQ(parsePreviewRange("--preview-range", "0,10"), glm::dvec2(0, 10));
  EXPECT_EQ(parsePreviewRange("--preview-range", "2.5,7"), glm::dvec2(2.5, 7));
  const std::pair<const char*, const char*> bad[] = {
      {"5,2", "NEAR 5 must be less than FAR 2"},
      {"3,3", "must be less than FAR"},
      {"-1,2", "NEAR -1 must be >= 0"},
      {"nan,2", "non-finite"},
      {"1,inf", "non-finite"},
      {"1", "expected"},
      {"a,b", "is not a number"},
  };
  for (const auto& [text, expect] : bad) {
    const std::string message = errorOf([&] { parsePreviewRange("--preview-range", text); });
    EXPECT_EQ(message.rfind("--preview-range: ", 0), 0u) << message;
    EXPECT_NE(message.find(text), std::string::npos) << message;
    EXPECT_NE(message.find(expect), std::string::npos) << message;
  }
  const std::string message =
      errorOf([] { checkPreviewable("--preview", "p.png", kAovPosition | kAovDistance); });
  EXPECT_NE(message.find("--preview: 'p.png': none of the AOVs distance,position can be "
                         "previewed (previewable: color,depth,normal,primid,geomid,instance,mesh,"
                         "material,albedo)"),
            std::string::npos)
      << message;
  EXPECT_EQ(errorOf([] { checkPreviewable("--preview", "p.png", kAovPosition | kAovGeomId); }), "");
}

/// The 8-bit RGB pixels of an image file, read by OpenImageIO (empty when unreadable).
std::vector<uint8_t> readRgb8(const std::string& path, int width, int height) {
  const test::DecodedImage<uint8_t> image = test::readImageFile<uint8_t>(path);
  EXPECT_EQ(image.info.width, width) << path;
  EXPECT_EQ(image.info.height, height) << path;
  EXPECT_EQ(image.info.channels, 3) << path;
  return image.info.channels == 3 ? image.samples : std::vector<uint8_t>{};
}

/// Every supported preview extension is one OpenImageIO writes here, as 3 8-bit channels, with
/// the pixels of the PNG (JPEG: within its loss, a mean error under 4 of 255; its chroma is
/// interpolated across block edges).
TEST(Outputs, EverySupportedPreviewExtensionIsWritten) {
  const std::string dir = test::scratchDir();
  // 16x16 blocks of one ID: JPEG's 16x16 macroblocks each see one colour.
  Framebuffer fb(48, 32, kAovPrimId);
  for (size_t i = 0; i < fb.pixelCount(); ++i)
    fb.primId[i] = uint32_t(i % 48 / 16 + i / 48 / 16 * 3);
  writePreview(dir + "/reference.png", fb);
  const std::vector<uint8_t> reference = readRgb8(dir + "/reference.png", 48, 32);
  for (const std::string& ext : supportedExtensions(OutputKind::Preview)) {
    const std::string path = dir + "/p" + ext;
    ASSERT_EQ(errorOf([&] { writePreview(path, fb); }), "") << ext;
    const std::vector<uint8_t> rgb = readRgb8(path, 48, 32);
    ASSERT_EQ(rgb.size(), reference.size()) << ext;
    int maxError = 0;
    double sumError = 0;
    for (size_t i = 0; i < rgb.size(); ++i) {
      const int e = std::abs(int(rgb[i]) - int(reference[i]));
      maxError = std::max(maxError, e);
      sumError += e;
    }
    if (ext == ".jpg" || ext == ".jpeg")
      EXPECT_LT(sumError / double(rgb.size()), 4.0) << ext;
    else
      EXPECT_EQ(maxError, 0) << ext;
  }
  EXPECT_EQ(filesUnder(dir).size(), supportedExtensions(OutputKind::Preview).size() + 1)
      << "no temporary file remains";
}

CameraParams lookAt(const glm::dvec3& eye, const glm::dvec3& at) {
  CameraParams p;
  p.eye = eye;
  p.at = at;
  p.fovDeg = 40;
  p.width = 32;
  p.height = 32;
  return p;
}

TEST(Outputs, DepthRangeOfABoxOverCameras) {
  const glm::dvec3 lo(-1.0), hi(1.0);
  // Looking down -Z from z = 10: corners at z = +-1 are at depths 9 and 11.
  auto range = depthRangeOfBox(lo, hi, {lookAt({0, 0, 10}, {0, 0, 0})});
  ASSERT_TRUE(range);
  EXPECT_NEAR(range->x, 9, 1e-12);
  EXPECT_NEAR(range->y, 11, 1e-12);
  // Diagonal view: the corner depths are (d -+ sqrt(3)) along the diagonal.
  const double d = 10 * std::sqrt(3.0);
  range = depthRangeOfBox(lo, hi, {lookAt({10, 10, 10}, {0, 0, 0})});
  ASSERT_TRUE(range);
  EXPECT_NEAR(range->x, d - std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(range->y, d + std::sqrt(3.0), 1e-9);
  // Several cameras: the union.
  range = depthRangeOfBox(lo, hi, {lookAt({0, 0, 10}, {0, 0, 0}), lookAt({20, 0, 0}, {0, 0, 0})});
  ASSERT_TRUE(range);
  EXPECT_NEAR(range->x, 9, 1e-12);
  EXPECT_NEAR(range->y, 21, 1e-12);
  // Inside the box NEAR is 0; a box wholly behind the camera has no range.
  range = depthRangeOfBox(lo, hi, {lookAt({0, 0, 0.5}, {0, 0, -1})});
  ASSERT_TRUE(range);
  EXPECT_EQ(range->x, 0.0);
  EXPECT_NEAR(range->y, 1.5, 1e-12);
  EXPECT_FALSE(depthRangeOfBox(lo, hi, {lookAt({0, 0, 5}, {0, 0, 10})}));
  EXPECT_FALSE(depthRangeOfBox(lo, hi, {}));
}

TEST(Outputs, PatternDirectoryIsTheFixedPart) {
  EXPECT_EQ(patternDirectory("out/{camera}/{frame}.exr"), "out/");
  EXPECT_EQ(patternDirectory("a/b/c_{frame}.exr"), "a/b/");
  EXPECT_EQ(patternDirectory("{camera}/f.exr"), ".");
  EXPECT_EQ(patternDirectory("f.exr"), ".");
  EXPECT_EQ(patternDirectory("/abs/x.exr"), "/abs/");
}

}  // namespace
