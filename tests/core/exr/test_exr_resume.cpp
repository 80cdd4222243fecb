// The core pieces `aperture batch --resume` relies on: EXR headers read without pixels, the
// channel names the EXR writer gives each AOV, and the one definition of temporary names.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "core/exr/exr.h"
#include "core/io/atomic_file.h"
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

TEST(ResumeIo, TemporaryNamesParseBackToTheirParts) {
  const std::string pid = std::to_string(::getpid());
  for (const std::string& suffix : {std::string(), std::string(".png")}) {
    for (const std::string& name : {std::string("out.exr"), std::string("a.tmp-1-2.exr")}) {
      const std::string tmp = temporaryPathFor("/d/" + name, suffix);
      ASSERT_EQ(tmp.rfind("/d/.", 0), 0u) << tmp;
      const auto parsed = parseTemporaryName(tmp.substr(3));
      ASSERT_TRUE(parsed.has_value()) << tmp;
      EXPECT_EQ(parsed->finalName, name);
      EXPECT_EQ(std::to_string(parsed->pid), pid);
      EXPECT_EQ(parsed->suffix, suffix);
    }
  }
  const auto t = parseTemporaryName(".frame_0001.exr.tmp-4242-17");
  ASSERT_TRUE(t.has_value());
  EXPECT_EQ(t->finalName, "frame_0001.exr");
  EXPECT_EQ(t->pid, 4242);
  EXPECT_EQ(t->counter, 17u);
  EXPECT_EQ(t->suffix, "");
  // Not temporaries: no leading dot, no counter, a PID that is not a number, a suffix that
  // does not start with '.', no name, a directory part.
  for (const char* name : {"frame.exr.tmp-4242-17", ".frame.exr.tmp-4242", ".frame.exr.tmp-pid-1",
                           ".frame.exr.tmp-4242-17x", ".tmp-4242-1", "d/.f.exr.tmp-1-2",
                           ".frame.exr", ".frame.exr.tmp--1"})
    EXPECT_FALSE(parseTemporaryName(name).has_value()) << name;
}

}  // namespace
}  // namespace aperture
