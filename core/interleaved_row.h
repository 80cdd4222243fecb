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

namespace interleaved_row {
using F4 = float __attribute__((vector_size(16)));
using I4 = int __attribute__((vector_size(16)));

inline F4 load(const float* p) {
  F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

/// Stores the kV vectors `out` to row[0 .. 4·kV).
template <int kV>
inline void store(const F4 (&out)[kV], float* row) {
  for (int k = 0; k < kV; ++k) std::memcpy(row + 4 * k, &out[k], sizeof out[k]);
}

/// Writes float i of vector k of `out` to row[4k + i] where keep[k][i] is −1, keeping the
/// row's old float where it is 0: one 16-byte load, select and store per vector (a block copy
/// of the arrays would pass through the stack and stall on store forwarding).
template <int kV>
inline void blend(const F4 (&out)[kV], const I4 (&keep)[kV], float* row) {
  for (int k = 0; k < kV; ++k) {
    const F4 blended = keep[k] ? out[k] : load(row + 4 * k);
    std::memcpy(row + 4 * k, &blended, sizeof blended);
  }
}

/// −1 in lane j where hit[j] != 0, else 0.
inline I4 hitMask(const int* hit) {
  I4 h;
  std::memcpy(&h, hit, sizeof h);
  return h != I4{0, 0, 0, 0};
}
}  // namespace interleaved_row

/// Writes pixel j (j = 0..3) of `row` (3 floats per pixel) as (x[j], y[j], z[j]) where
/// hit[j] != 0, leaving the other pixels as they are; `bits` is rowHitBits(hit). `row` needs
/// no alignment.
inline void blendInterleavedRow4x3(const float* x, const float* y, const float* z, const int* hit,
                                   unsigned bits, float* row) {
  using interleaved_row::F4;
  if (bits == 0) return;
  const F4 vx = interleaved_row::load(x), vy = interleaved_row::load(y),
           vz = interleaved_row::load(z);
  // Three vectors of four floats: x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3.
  const F4 xy01 = __builtin_shufflevector(vx, vy, 0, 4, 1, 5);  // x0 y0 x1 y1
  const F4 yz12 = __builtin_shufflevector(vy, vz, 1, 5, 2, 6);  // y1 z1 y2 z2
  const F4 xy33 = __builtin_shufflevector(vx, vy, 3, 7, 3, 7);  // x3 y3 x3 y3
  const F4 out[3] = {__builtin_shufflevector(xy01, vz, 0, 1, 4, 2),
                     __builtin_shufflevector(yz12, vx, 0, 1, 6, 2),
                     __builtin_shufflevector(xy33, vz, 6, 0, 1, 7)};
  if (bits == kWholeRow) return interleaved_row::store(out, row);
  const interleaved_row::I4 m = interleaved_row::hitMask(hit);
  const interleaved_row::I4 keep[3] = {__builtin_shufflevector(m, m, 0, 0, 0, 1),
                                       __builtin_shufflevector(m, m, 1, 1, 2, 2),
                                       __builtin_shufflevector(m, m, 2, 3, 3, 3)};
  interleaved_row::blend(out, keep, row);
}

}  // namespace aperture
