#pragma once
// One row of four pixels of a framebuffer channel, written from the frame loop's lanes with a
// mask: the pixels whose lane hit get the lane's values, the others keep theirs. The caller
// gives the row's hit bits, taken once per packet for all of its channels. The old pixels
// are read back only for a row that is partly hit: a whole row of misses is left alone, and a
// whole row of hits (the common case) is stored without reading the old pixels, whose cache
// lines may not be loaded yet (a load that misses stalls the blend that needs it; a store does
// not stall).
//  - blendRow4: one 32-bit value a pixel (depth, distance, primID, geomID).
//  - blendInterleavedRow4x3: interleaved x y z floats (normals, positions). GCC's vectorisers
//    emitted this transpose-and-blend as one read-back and store per component; the normal
//    store was a third of `bench --null --aov depth,normal` (bench/RESULTS.md, issue 13).
// The transpose is 4-wide shuffles and selects, which every x86-64 level has (SSE2 and up)
// and which only move bits (`__builtin_shufflevector`: GCC 12 and Clang both have it; the fuzz
// builds are Clang's).
#include <cstring>

namespace aperture {

/// A row of four lanes' hit bits: bit j set where hit[j] != 0. The writers below take it.
inline unsigned rowHitBits(const int* hit) {
  return unsigned(hit[0] != 0) | unsigned(hit[1] != 0) << 1 | unsigned(hit[2] != 0) << 2 |
         unsigned(hit[3] != 0) << 3;
}
inline constexpr unsigned kWholeRow = 0xFu;  ///< rowHitBits of a row whose four lanes hit

/// Writes pixel j (j = 0..3) of `row` as value[j] where hit[j] != 0, leaving the other pixels
/// as they are; `bits` is rowHitBits(hit). T is a 32-bit type (float or uint32_t); `row` needs
/// no alignment.
template <class T>
inline void blendRow4(const T* value, const int* hit, unsigned bits, T* row) {
  static_assert(sizeof(T) == 4, "one 32-bit value a pixel");
  if (bits == 0) return;
  if (bits == kWholeRow) {
    std::memcpy(row, value, 4 * sizeof(T));
    return;
  }
  for (int j = 0; j < 4; ++j) row[j] = hit[j] ? value[j] : row[j];
}

/// Writes pixel j (j = 0..3) of `row` (3 floats per pixel) as (x[j], y[j], z[j]) where
/// hit[j] != 0, leaving the other pixels as they are; `bits` is rowHitBits(hit). `row` needs
/// no alignment.
inline void blendInterleavedRow4x3(const float* x, const float* y, const float* z, const int* hit,
                                   unsigned bits, float* row) {
  using F4 = float __attribute__((vector_size(16)));
  using I4 = int __attribute__((vector_size(16)));
  if (bits == 0) return;
  F4 vx, vy, vz;
  std::memcpy(&vx, x, sizeof vx);
  std::memcpy(&vy, y, sizeof vy);
  std::memcpy(&vz, z, sizeof vz);
  // Three vectors of four floats: x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3.
  const F4 xy01 = __builtin_shufflevector(vx, vy, 0, 4, 1, 5);  // x0 y0 x1 y1
  const F4 yz12 = __builtin_shufflevector(vy, vz, 1, 5, 2, 6);  // y1 z1 y2 z2
  const F4 xy33 = __builtin_shufflevector(vx, vy, 3, 7, 3, 7);  // x3 y3 x3 y3
  const F4 out[3] = {__builtin_shufflevector(xy01, vz, 0, 1, 4, 2),
                     __builtin_shufflevector(yz12, vx, 0, 1, 6, 2),
                     __builtin_shufflevector(xy33, vz, 6, 0, 1, 7)};
  if (bits == kWholeRow) {
    for (int k = 0; k < 3; ++k) std::memcpy(row + 4 * k, &out[k], sizeof out[k]);
    return;
  }
  I4 h;
  std::memcpy(&h, hit, sizeof h);
  const I4 m = h != I4{0, 0, 0, 0};  // −1 where the lane hit
  const I4 mask[3] = {__builtin_shufflevector(m, m, 0, 0, 0, 1),
                      __builtin_shufflevector(m, m, 1, 1, 2, 2),
                      __builtin_shufflevector(m, m, 2, 3, 3, 3)};
  // One 16-byte load, select and store per vector (a block copy of the arrays would pass
  // through the stack and stall on store forwarding).
  for (int k = 0; k < 3; ++k) {
    F4 old;
    std::memcpy(&old, row + 4 * k, sizeof old);
    const F4 blended = mask[k] ? out[k] : old;
    std::memcpy(row + 4 * k, &blended, sizeof blended);
  }
}

}  // namespace aperture
