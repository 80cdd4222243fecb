#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>

#include "core/engine/interleaved_row.h"

namespace aperture {
namespace {

// Every one of the 16 hit masks, against the per-pixel definition: pixel j of the row is
// (x[j], y[j], z[j]) where hit[j] != 0 and keeps its old values elsewhere; the floats after
// the row's 12 are never touched. Values are distinct, so any wrong shuffle index shows.
TEST(InterleavedRow, EveryMaskMatchesThePerPixelDefinition) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(-1.0f, 1.0f);
  for (int mask = 0; mask < 16; ++mask) {
    float x[4], y[4], z[4];
    int hit[4];
    for (int j = 0; j < 4; ++j) {
      x[j] = value(rng), y[j] = value(rng), z[j] = value(rng);
      hit[j] = (mask >> j) & 1 ? 1 + j : 0;  // any non-zero value is a hit
    }
    std::array<float, 16> row{}, expected{};
    for (size_t k = 0; k < row.size(); ++k) row[k] = expected[k] = 100.0f + float(k);
    for (int j = 0; j < 4; ++j)
      if (hit[j]) {
        expected[size_t(3 * j)] = x[j];
        expected[size_t(3 * j + 1)] = y[j];
        expected[size_t(3 * j + 2)] = z[j];
      }
    blendInterleavedRow4x3(x, y, z, hit, rowHitBits(hit), row.data());
    for (size_t k = 0; k < row.size(); ++k)
      EXPECT_EQ(row[k], expected[k]) << "mask " << mask << ", float " << k;
  }
}

TEST(InterleavedRow, HitBitsMarkNonZeroLanes) {
  const int none[4] = {0, 0, 0, 0}, some[4] = {-1, 0, 7, 0}, all[4] = {1, -1, 2, 3};
  EXPECT_EQ(rowHitBits(none), 0u);
  EXPECT_EQ(rowHitBits(some), 0b0101u);
  EXPECT_EQ(rowHitBits(all), kWholeRow);
}

// The row needs no alignment: an odd offset into a buffer gives the same values.
TEST(InterleavedRow, UnalignedRowsAreWrittenTheSame) {
  const float x[4] = {1, 2, 3, 4}, y[4] = {5, 6, 7, 8}, z[4] = {9, 10, 11, 12};
  const int hit[4] = {1, 0, 1, 1};
  std::array<float, 17> buffer{};
  blendInterleavedRow4x3(x, y, z, hit, rowHitBits(hit), buffer.data() + 1);
  const std::array<float, 17> expected{0, 1, 5, 9, 0, 0, 0, 3, 7, 11, 4, 8, 12, 0, 0, 0, 0};
  EXPECT_EQ(buffer, expected);
}

// blendRow4, for every one of the 16 hit masks and both 32-bit types, against the per-pixel
// definition: pixel j is value[j] where hit[j] != 0 and keeps its old value elsewhere; the
// values after the row's four are never touched.
template <class T>
void checkEveryMaskOfBlendRow4() {
  for (int mask = 0; mask < 16; ++mask) {
    T value[4];
    int hit[4];
    for (int j = 0; j < 4; ++j) {
      value[j] = T(10 + j);
      hit[j] = (mask >> j) & 1 ? -1 - j : 0;  // any non-zero value is a hit
    }
    std::array<T, 6> row{}, expected{};
    for (size_t k = 0; k < row.size(); ++k) row[k] = expected[k] = T(100 + k);
    for (int j = 0; j < 4; ++j)
      if (hit[j]) expected[size_t(j)] = value[j];
    blendRow4<T>(value, hit, rowHitBits(hit), row.data());
    for (size_t k = 0; k < row.size(); ++k)
      EXPECT_EQ(row[k], expected[k]) << "mask " << mask << ", pixel " << k;
  }
}

TEST(InterleavedRow, BlendRow4MatchesThePerPixelDefinitionForEveryMask) {
  checkEveryMaskOfBlendRow4<float>();
  checkEveryMaskOfBlendRow4<uint32_t>();
}

}  // namespace
}  // namespace aperture
