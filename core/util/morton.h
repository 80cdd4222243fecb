#pragma once
// Morton (Z-order) codes: the bits of a cell's coordinates interleaved, so that cells near in
// space are mostly near in the order (triangle order in the BVH build, query points).
#include <cstdint>

namespace aperture {

/// x's low 21 bits spread to every third bit (bit b to bit 3b): one axis of a Morton code
/// (axis a shifted left by a).
constexpr uint64_t spreadBits(uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

}  // namespace aperture
