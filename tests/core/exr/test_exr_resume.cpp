// The EXR pieces `aperture batch --resume` relies on (core/exr/exr.h): headers read without
// pixels, and the channel names the EXR writer gives each AOV.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "core/exr/exr.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;

/// The channel names of an EXR as OpenEXR itself lists them (independent of readExrHeader).
std::vector<std::string> channelsByOpenExr(const std::string& path) {
  Imf::InputFile file(path.c_str());
  std::vector<std::string> names;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
    names.emplace_back(it.name());
  return names;
}

std::vector<std::string> sorted(std::vector<std::string> v) {
  std::sort(v.begin(), v.end());
  return v;
}

TEST(ResumeIo, ChannelNamesAreWhatTheWriterWritesForEveryAov) {
  const std::string dir = test::scratchDir();
  const AovMask all = parseAovList("all");
  // Every single AOV, and all of them together.
  std::vector<AovMask> masks = {all};
  for (AovMask bit = 1; bit & all; bit <<= 1) masks.push_back(bit);
  for (AovMask mask : masks) {
    SCOPED_TRACE(aovListString(mask));
    const std::string path = dir + "/m" + std::to_string(mask) + ".exr";
    writeExr(path, Framebuffer(5, 3, mask), ExrMetadata{});
    const std::vector<std::string> names = exrChannelNames(mask);
    EXPECT_EQ(sorted(names), sorted(channelsByOpenExr(path)));
    EXPECT_EQ(sorted(readExrHeader(path).channels), sorted(channelsByOpenExr(path)));
  }
  EXPECT_EQ(exrChannelNames(kAovNormal), (std::vector<std::string>{"N.X", "N.Y", "N.Z"}));
  EXPECT_EQ(exrChannelNames(all).size(), 14u);  // RGBA, Z, T, N.XYZ, P.XYZ, primID, geomID
}

TEST(ResumeIo, HeaderIsReadWithoutPixelsAndMatchesReadExr) {
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/h.exr";
  ExrMetadata meta;
  meta.camera.type = "orthographic";
  meta.camera.eye = {1.25, -2, 3e5};
  meta.camera.d = 2;
  meta.camera.vw = 3;
  meta.camera.vh = 1.5;
  meta.camera.spp = 4;
  meta.camera.extra = {{"shift", "0.1,0"}};
  writeExr(path, Framebuffer(7, 5, kAovColor | kAovDepth), meta);
  const ExrHeader h = readExrHeader(path);
  EXPECT_EQ(h.width, 7);
  EXPECT_EQ(h.height, 5);
  EXPECT_EQ(h.meta.camera.type, "orthographic");
  EXPECT_EQ(h.meta.camera.eye, meta.camera.eye);
  EXPECT_EQ(h.meta.camera.vh, 1.5);
  EXPECT_EQ(h.meta.camera.spp, 4);
  EXPECT_EQ(h.meta.camera.extra, meta.camera.extra);

  // Truncated after the header: the header still reads, the pixels do not.
  fs::resize_file(path, fs::file_size(path) - 40);
  EXPECT_EQ(readExrHeader(path).width, 7);
  EXPECT_FALSE(isCompleteExr(path));
  test::writeFile(dir + "/junk.exr", "not an EXR at all");
  try {
    readExrHeader(dir + "/junk.exr");
    FAIL() << "no error for a file that is not an EXR";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("junk.exr"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace aperture
