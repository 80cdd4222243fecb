// Point clouds as columns and the destagger of range images (core/points/point_cloud.h),
// against np.roll's definition of a row shift (what ouster-sdk's destagger does per row):
// out[(c + shift) mod w] = in[c]; tests/python/test_scan_formats.py checks it against the SDK.
#include <gtest/gtest.h>

#include <vector>

#include "core/points/point_cloud.h"
#include "tests/support.h"

namespace aperture {
namespace {

TEST(PointCloud, FieldsHoldTheirValues) {
  PointCloud c;
  c.size = 3;
  auto* r = c.add<uint16_t>("ring", PointType::UInt16);
  auto* t = c.add<double>("x", PointType::Float64);
  r[2] = 65535;
  t[1] = -0.125;
  EXPECT_EQ(c.find("ring")->value(2), 65535.0);
  EXPECT_EQ(c.find("x")->value(1), -0.125);
  EXPECT_EQ(c.find("ring")->count(), 3u);
  EXPECT_EQ(c.find("nothing"), nullptr);
  EXPECT_NE(test::errorOf([&] { c.add<float>("x", PointType::Float32); }).find("'x'"),
            std::string::npos);
  c.check("cloud");
}

TEST(PointCloud, DestaggerShiftsEachRowAsARoll) {
  const int rows = 3, cols = 5;
  const std::vector<int> shifts = {0, 2, -7};
  PointField f;
  f.name = "RANGE";
  f.type = PointType::UInt32;
  f.bytes.resize(4 * rows * cols);
  for (int i = 0; i < rows * cols; ++i) f.as<uint32_t>()[i] = uint32_t(100 + i);
  const PointField d = destagger(f, rows, cols, shifts);
  for (int u = 0; u < rows; ++u)
    for (int c = 0; c < cols; ++c) {
      const int to = (((c + shifts[size_t(u)]) % cols) + cols) % cols;
      EXPECT_EQ(d.as<uint32_t>()[u * cols + to], f.as<uint32_t>()[u * cols + c]) << u << "," << c;
    }
  const PointField back = destagger(d, rows, cols, shifts, true);
  EXPECT_EQ(back.bytes, f.bytes);
}

}  // namespace
}  // namespace aperture
