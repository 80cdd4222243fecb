#pragma once
// Per-ISA code in the portable build. The build carries no -march flag (APERTURE_NATIVE is
// off by default), so the hot loops (ray generation, the frame loop's AOV stores) are marked
// APERTURE_VECTOR_KERNEL: GCC and Clang compile the function once per x86-64 level (v4:
// AVX-512, v3: AVX2 + FMA, and the baseline) and pick one at load time through an ifunc, as
// Embree dispatches its own kernels. Everything inlined into a kernel is compiled for the
// kernel's level too: kernels are `flatten`ed, so every call they make that can be inlined
// is, and runs at the kernel's level (a call left out of line would run the baseline code). GCC
// only: Clang builds (the fuzz targets) get the baseline code.
//
// Rules for a kernel:
//  - a free function (GCC cannot clone virtual functions): a camera's virtual generate() calls
//    its kernel with the camera's constants;
//  - results are bit-identical on every level: the build has -ffp-contract=off (no FMA
//    contraction) and no fast-math, and IEEE +, −, ×, ÷ and √ round the same in every
//    vector width. tests/cameras/test_golden.cpp holds the hashes.
//
// Lane loops (for k over a packet's N lanes, N a constant) are marked APERTURE_LANE_LOOP. GCC
// otherwise unrolls such a loop completely before its loop vectoriser runs and leaves the
// straight-line code to the weaker basic-block vectoriser, which on the frame loop emitted
// scalar and partial-width code: `bench --null` measured 4.2 ns/ray with it and 3.0 without
// (bench/RESULTS.md, issue 13). Not unrolling lets the loop vectoriser take the whole loop, at
// N lanes a single vector iteration. Nothing changes but the instruction selection.
#include <cmath>
#include <limits>

#if defined(__GNUC__) && !defined(__clang__)
#define APERTURE_LANE_LOOP _Pragma("GCC unroll 1")
#else
#define APERTURE_LANE_LOOP
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(APERTURE_NO_ISA_CLONES)
#define APERTURE_VECTOR_KERNEL \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"), flatten))
#else
#define APERTURE_VECTOR_KERNEL __attribute__((flatten))
#endif

namespace aperture {

/// Whether x is finite, as a comparison that vectorises in a lane loop (std::isfinite does
/// not): false for ±inf and NaN.
template <class T>
inline bool finiteLane(T x) {
  return std::fabs(x) <= std::numeric_limits<T>::max();
}

}  // namespace aperture
