// The point-cloud writers (core/points/point_writers.h) against their specs: every header and
// record is parsed here byte by byte, independently of the writers, and compared with the
// values put in. PLY and PCD: Greg Turk's PLY and PCL's PCD v0.7 layouts; LAS: the ASPRS LAS
// 1.4 R15 public header block (375 bytes, field offsets from the spec's table) and point data
// record format 6 (30 bytes); KITTI: float32 x y z intensity and SemanticKITTI's uint32
// labels. Python readers (laspy, pypcd4, NumPy) read the same files in
// tests/python/test_scan_formats.py.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/points/point_writers.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;

template <typename T>
T at(const std::string& bytes, size_t offset) {
  T v;
  EXPECT_LE(offset + sizeof(T), bytes.size());
  if (offset + sizeof(T) > bytes.size()) return T{};
  std::memcpy(&v, bytes.data() + offset, sizeof(T));
  return v;
}

/// Five points with every standard field and a label; positions far from the origin in x.
PointCloud sampleCloud() {
  namespace pf = point_fields;
  PointCloud c;
  c.size = 5;
  c.startSeconds = 1000.25;
  auto* x = c.add<double>(pf::kX, PointType::Float64);
  auto* y = c.add<double>(pf::kY, PointType::Float64);
  auto* z = c.add<double>(pf::kZ, PointType::Float64);
  auto* range = c.add<float>(pf::kRange, PointType::Float32);
  auto* time = c.add<uint32_t>(pf::kTime, PointType::UInt32);
  auto* ring = c.add<uint16_t>(pf::kRing, PointType::UInt16);
  auto* intensity = c.add<float>(pf::kIntensity, PointType::Float32);
  auto* instance = c.add<uint32_t>(pf::kInstance, PointType::UInt32);
  auto* label = c.add<uint32_t>("semantic", PointType::UInt32);
  for (size_t i = 0; i < c.size; ++i) {
    x[i] = 1000.0 + 1.2345 * double(i);
    y[i] = -2.5 + 0.001 * double(i);
    z[i] = 0.25 * double(i);
    range[i] = float(3.0 + double(i));
    time[i] = uint32_t(12345 * i);
    ring[i] = uint16_t(i * 30);
    intensity[i] = float(0.3 * double(i));  // 1.2 for the last: clamped in LAS
    instance[i] = uint32_t(7 + i);
    label[i] = uint32_t(40 + i);
  }
  return c;
}

/// `name` in the test's scratch directory (emptied at each call: one call per test).
std::string scratch(const std::string& name) { return test::scratchDir() + "/" + name; }

TEST(PointWriters, FormatByExtension) {
  EXPECT_EQ(pointFormatOf("a/b.PLY"), PointFormat::Ply);
  EXPECT_EQ(pointFormatOf("x.pcd"), PointFormat::Pcd);
  EXPECT_EQ(pointFormatOf("x.las"), PointFormat::Las);
  EXPECT_EQ(pointFormatOf("x.bin"), PointFormat::KittiBin);
  EXPECT_EQ(pointFormatOf("x.npz"), PointFormat::Npz);
  EXPECT_EQ(pointFormatOf("x.exr"), PointFormat::Exr);
  const std::string e = test::errorOf([] { pointFormatOf("scans/a.xyz"); });
  EXPECT_NE(e.find("scans/a.xyz"), std::string::npos) << e;
  EXPECT_NE(e.find(".las"), std::string::npos) << e;
  EXPECT_TRUE(isRangeImageFormat(PointFormat::Npz));
  EXPECT_FALSE(isRangeImageFormat(PointFormat::Las));
}

TEST(PointWriters, PlyHeaderAndRecords) {
  const PointCloud c = sampleCloud();
  const std::string path = scratch("cloud.ply");
  writePointsPly(path, c, {"", {"frame sensor"}});
  const std::string bytes = test::readFile(path);
  const std::string expected =
      "ply\nformat binary_little_endian 1.0\ncomment frame sensor\nelement vertex 5\n"
      "property double x\nproperty double y\nproperty double z\nproperty float range\n"
      "property uint time\nproperty ushort ring\nproperty float intensity\n"
      "property uint instance\nproperty uint semantic\nend_header\n";
  ASSERT_EQ(bytes.substr(0, expected.size()), expected);
  const size_t record = 8 * 3 + 4 + 4 + 2 + 4 + 4 + 4;
  ASSERT_EQ(bytes.size(), expected.size() + 5 * record);
  for (size_t i = 0; i < 5; ++i) {
    const size_t o = expected.size() + i * record;
    EXPECT_EQ(at<double>(bytes, o), 1000.0 + 1.2345 * double(i));
    EXPECT_EQ(at<double>(bytes, o + 16), 0.25 * double(i));
    EXPECT_EQ(at<uint32_t>(bytes, o + 28), uint32_t(12345 * i));
    EXPECT_EQ(at<uint16_t>(bytes, o + 32), uint16_t(30 * i));
    EXPECT_EQ(at<uint32_t>(bytes, o + 42), uint32_t(40 + i));
  }
}

TEST(PointWriters, PcdHeaderAndRecords) {
  const PointCloud c = sampleCloud();
  const std::string path = scratch("cloud.pcd");
  writePointsPcd(path, c);
  const std::string bytes = test::readFile(path);
  const std::string expected =
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
      "FIELDS x y z range time ring intensity instance semantic\n"
      "SIZE 8 8 8 4 4 2 4 4 4\nTYPE F F F F U U F U U\nCOUNT 1 1 1 1 1 1 1 1 1\n"
      "WIDTH 5\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 5\nDATA binary\n";
  ASSERT_EQ(bytes.substr(0, expected.size()), expected);
  const size_t record = 46;
  ASSERT_EQ(bytes.size(), expected.size() + 5 * record);
  EXPECT_EQ(at<float>(bytes, expected.size() + 4 * record + 24), 7.0f);
  EXPECT_EQ(at<float>(bytes, expected.size() + 3 * record + 34), float(0.3 * 3.0));
}

TEST(PointWriters, LasHeaderAndFormat6Records) {
  const PointCloud c = sampleCloud();
  const std::string path = scratch("cloud.las");
  writePointsLas(path, c, {"semantic", {}});
  const std::string b = test::readFile(path);
  ASSERT_EQ(b.size(), 375u + 5u * 30u);
  EXPECT_EQ(b.substr(0, 4), "LASF");
  EXPECT_EQ(at<uint16_t>(b, 6) & 0x10u, 0x10u);  // WKT bit, required for formats 6-10
  EXPECT_EQ(at<uint8_t>(b, 24), 1);
  EXPECT_EQ(at<uint8_t>(b, 25), 4);
  EXPECT_EQ(at<uint16_t>(b, 94), 375);
  EXPECT_EQ(at<uint32_t>(b, 96), 375u);
  EXPECT_EQ(at<uint32_t>(b, 100), 0u);
  EXPECT_EQ(at<uint8_t>(b, 104), 6);
  EXPECT_EQ(at<uint16_t>(b, 105), 30);
  EXPECT_EQ(at<uint32_t>(b, 107), 0u);  // legacy count: 0 for format 6
  double scale[3], offset[3];
  for (int a = 0; a < 3; ++a) {
    scale[a] = at<double>(b, 131 + 8 * size_t(a));
    offset[a] = at<double>(b, 155 + 8 * size_t(a));
    EXPECT_EQ(scale[a], 0.001);
  }
  EXPECT_EQ(offset[0], std::round(0.5 * (1000.0 + 1000.0 + 4 * 1.2345)));
  EXPECT_EQ(at<double>(b, 179), 1000.0 + 4 * 1.2345);  // max x
  EXPECT_EQ(at<double>(b, 187), 1000.0);               // min x
  EXPECT_EQ(at<double>(b, 219), 0.0);                  // min z
  EXPECT_EQ(at<uint64_t>(b, 247), 5u);
  EXPECT_EQ(at<uint64_t>(b, 255), 5u);  // all first returns
  EXPECT_EQ(at<uint64_t>(b, 263), 0u);
  for (size_t i = 0; i < 5; ++i) {
    const size_t o = 375 + 30 * i;
    const double x = at<int32_t>(b, o) * scale[0] + offset[0];
    const double y = at<int32_t>(b, o + 4) * scale[1] + offset[1];
    const double z = at<int32_t>(b, o + 8) * scale[2] + offset[2];
    EXPECT_NEAR(x, 1000.0 + 1.2345 * double(i), 0.5e-3 + 1e-9);
    EXPECT_NEAR(y, -2.5 + 0.001 * double(i), 0.5e-3 + 1e-9);
    EXPECT_NEAR(z, 0.25 * double(i), 0.5e-3 + 1e-9);
    const double level = std::min(1.0, double(float(0.3 * double(i))));
    EXPECT_EQ(at<uint16_t>(b, o + 12), uint16_t(std::lround(level * 65535.0)));
    EXPECT_EQ(at<uint8_t>(b, o + 14), 1 | (1 << 4));  // return 1 of 1
    EXPECT_EQ(at<uint8_t>(b, o + 16), 40 + i);        // classification from the label
    EXPECT_EQ(at<uint8_t>(b, o + 17), 30 * i);        // user data: the ring
    EXPECT_EQ(at<double>(b, o + 22), 1000.25 + double(12345 * i) * 1e-9);
  }
}

TEST(PointWriters, LasRefusesLabelsPastAByte) {
  PointCloud c = sampleCloud();
  c.find("semantic")->as<uint32_t>()[2] = 256;
  const std::string path = scratch("bad_label.las");
  const std::string e = test::errorOf([&] { writePointsLas(path, c, {"semantic", {}}); });
  EXPECT_NE(e.find("semantic"), std::string::npos) << e;
  EXPECT_NE(e.find("256"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(path));
}

TEST(PointWriters, KittiBinAndSemanticKittiLabel) {
  const PointCloud c = sampleCloud();
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/000042.bin";
  writePointsKitti(path, c, {"semantic", {}});
  EXPECT_EQ(kittiLabelPathOf(path), dir + "/000042.label");
  const std::string scan = test::readFile(path), labels = test::readFile(dir + "/000042.label");
  ASSERT_EQ(scan.size(), 5u * 16u);
  ASSERT_EQ(labels.size(), 5u * 4u);
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(at<float>(scan, 16 * i), float(1000.0 + 1.2345 * double(i)));
    EXPECT_EQ(at<float>(scan, 16 * i + 12), float(0.3 * double(i)));
    const uint32_t l = at<uint32_t>(labels, 4 * i);
    EXPECT_EQ(l & 0xFFFFu, 40u + i);
    EXPECT_EQ(l >> 16, 7u + i);
  }
}

TEST(PointWriters, KittiRefusesInstancesPastSixteenBitsAndLeavesNoFile) {
  PointCloud c = sampleCloud();
  c.find(point_fields::kInstance)->as<uint32_t>()[1] = 70000;
  const std::string path = scratch("000043.bin");
  const std::string e = test::errorOf([&] { writePointsKitti(path, c, {"semantic", {}}); });
  EXPECT_NE(e.find("70000"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(kittiLabelPathOf(path)));
}

TEST(PointWriters, FieldsOfTheWrongLengthAreRefused) {
  PointCloud c = sampleCloud();
  c.find(point_fields::kRange)->bytes.resize(8);
  const std::string path = scratch("short.ply");
  const std::string e = test::errorOf([&] { writePointsPly(path, c); });
  EXPECT_NE(e.find("range"), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace aperture
