// Range images as .npz and EXR (core/points/point_writers.h): read back with readNpz and
// readExrChannels, each channel equal to what was put in, its destaggered copy equal to the
// row roll computed here.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/exr/exr_channels.h"
#include "core/io/npz.h"
#include "core/points/point_writers.h"
#include "tests/support.h"

namespace aperture {
namespace {

RangeImage sampleImage() {
  RangeImage img;
  img.rows = 4;
  img.columns = 6;
  img.pixelShiftByRow = {3, 1, -1, -3};
  auto* range = img.addChannel("RANGE", PointType::UInt32).as<uint32_t>();
  auto* metres = img.addChannel("range", PointType::Float32).as<float>();
  for (int i = 0; i < img.rows * img.columns; ++i) {
    range[i] = i % 5 == 0 ? 0u : uint32_t(1000 + 37 * i);
    metres[i] = float(range[i]) * 0.001f;
  }
  return img;
}

uint32_t rolled(const RangeImage& img, int u, int c) {
  const int w = img.columns;
  const int from = (((c - img.pixelShiftByRow[size_t(u)]) % w) + w) % w;
  return img.find("RANGE")->as<uint32_t>()[u * w + from];
}

TEST(RangeImageWriter, NpzHoldsEveryChannelAndItsDestaggeredCopy) {
  const RangeImage img = sampleImage();
  const std::string path = test::scratchDir() + "/scan.npz";
  writeRangeImage(path, img);
  const auto members = readNpz(path);
  std::vector<std::string> names;
  for (const auto& [name, m] : members) names.push_back(name);
  EXPECT_EQ(names, (std::vector<std::string>{"RANGE", "range", "destaggered.RANGE",
                                             "destaggered.range", "pixel_shift_by_row"}));
  const NpzMember& range = members[0].second;
  EXPECT_EQ(range.descr, "<u4");
  EXPECT_EQ(range.shape, (std::vector<uint64_t>{4, 6}));
  EXPECT_EQ(std::memcmp(range.data.data(), img.find("RANGE")->bytes.data(), 4 * 24), 0);
  const NpzMember& destaggered = members[2].second;
  for (int u = 0; u < 4; ++u)
    for (int c = 0; c < 6; ++c) {
      uint32_t v;
      std::memcpy(&v, destaggered.data.data() + 4 * (u * 6 + c), 4);
      EXPECT_EQ(v, rolled(img, u, c)) << u << "," << c;
    }
}

TEST(RangeImageWriter, ExrHoldsUintAndFloatChannels) {
  const RangeImage img = sampleImage();
  const std::string path = test::scratchDir() + "/scan.exr";
  writeRangeImage(path, img);
  int w = 0, h = 0;
  const std::vector<ExrChannel> channels = readExrChannels(path, &w, &h);
  EXPECT_EQ(w, 6);
  EXPECT_EQ(h, 4);
  bool sawRange = false, sawDestaggered = false, sawMetres = false;
  for (const ExrChannel& c : channels) {
    if (c.name == "RANGE") {
      sawRange = true;
      ASSERT_TRUE(c.isUint());
      for (int i = 0; i < 24; ++i)
        EXPECT_EQ(c.uints[size_t(i)], img.find("RANGE")->as<uint32_t>()[i]);
    } else if (c.name == "destaggered.RANGE") {
      sawDestaggered = true;
      for (int u = 0; u < 4; ++u)
        for (int x = 0; x < 6; ++x) EXPECT_EQ(c.uints[size_t(u * 6 + x)], rolled(img, u, x));
    } else if (c.name == "range") {
      sawMetres = true;
      ASSERT_FALSE(c.isUint());
      for (int i = 0; i < 24; ++i)
        EXPECT_EQ(c.floats[size_t(i)], img.find("range")->as<float>()[i]);
    }
  }
  EXPECT_TRUE(sawRange && sawDestaggered && sawMetres);
}

TEST(RangeImageWriter, PointCloudFormatsAreNotRangeImages) {
  const std::string path = test::scratchDir() + "/scan.ply";
  const std::string e = test::errorOf([&] { writeRangeImage(path, sampleImage()); });
  EXPECT_NE(e.find("scan.ply"), std::string::npos) << e;
}

}  // namespace
}  // namespace aperture
