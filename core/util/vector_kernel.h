#pragma once
// Per-ISA code in the portable build. The build carries no -march flag (APERTURE_NATIVE is
// off by default), so the hot loops (ray generation, the frame loop's AOV stores) are
// **kernels**: a free function `f` called as runKernel<&f>(args...). Kernel<&f> compiles it
// once per x86-64 level (v4: AVX-512, v3: AVX2 + FMA, and the baseline), each a `flatten`ed
// copy with GCC's target attribute, so f and every call it makes that can be inlined run at
// that level (a call left out of line runs the baseline code). runKernel calls the copy of
// the level activeKernelIsa() chose once per process: the highest this CPU runs, or the one
// the environment variable APERTURE_KERNEL_ISA forces (x86-64-v4, x86-64-v3 or baseline), as
// APERTURE_EMBREE_CONFIG=isa=... forces Embree's. A plain switch on a cached value rather
// than GCC's target_clones: their ifunc resolvers run while the program is being relocated,
// before the environment can safely be read (and before ThreadSanitizer's runtime is up).
// GCC on x86-64 only: Clang builds (the fuzz targets) and the sanitizer builds
// (APERTURE_NO_ISA_CLONES) compile each kernel once, at the baseline level.
//
// Rules for a kernel:
//  - a free function, or an instance of a function template (a camera's virtual generate()
//    calls its kernel with the camera's constants);
//  - results are bit-identical on every level: the build has -ffp-contract=off (no FMA
//    contraction) and no fast-math, and IEEE +, −, ×, ÷ and √ round the same in every
//    vector width. tests/cameras/models/test_golden.cpp holds the hashes, and CI runs the suite
//    with each level forced (scripts/ci-isa.sh).
//
// Lane loops (for k over a packet's N lanes, N a constant) are marked APERTURE_LANE_LOOP. GCC
// otherwise unrolls such a loop completely before its loop vectoriser runs and leaves the
// straight-line code to the weaker basic-block vectoriser, which on the frame loop emitted
// scalar and partial-width code: `bench --null` measured 4.2 ns/ray with it and 3.0 without
// (bench/RESULTS.md, issue 13). Not unrolling lets the loop vectoriser take the whole loop, at
// N lanes a single vector iteration. Nothing changes but the instruction selection.
#include <cmath>
#include <limits>
#include <string>

#if defined(__GNUC__) && !defined(__clang__)
#define APERTURE_LANE_LOOP _Pragma("GCC unroll 1")
#else
#define APERTURE_LANE_LOOP
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(APERTURE_NO_ISA_CLONES)
#define APERTURE_ISA_CLONES 1
#else
#define APERTURE_ISA_CLONES 0
#endif

namespace aperture {

/// The x86-64 levels a kernel is compiled for, lowest first.
enum class KernelIsa { Baseline, V3, V4 };

/// The name APERTURE_KERNEL_ISA takes: "baseline", "x86-64-v3", "x86-64-v4".
const char* kernelIsaName(KernelIsa isa);

/// The highest level this CPU runs (__builtin_cpu_supports: the level's instructions and the
/// operating system's support for their registers).
KernelIsa cpuKernelIsa();

/// The highest level this build compiled its kernels for: x86-64-v4 with clones, else the
/// baseline.
KernelIsa builtKernelIsa();

/// The level named by `value` (APERTURE_KERNEL_ISA's value; null or empty: unset, which picks
/// the highest both `cpu` and `built` allow). An unknown name, or a level above `cpu` or
/// `built`, is an Error naming the variable and the value.
KernelIsa chooseKernelIsa(const char* value, KernelIsa cpu, KernelIsa built);

/// The level this process runs its kernels at: chooseKernelIsa of the environment, the CPU
/// and the build, decided on the first call (which throws what chooseKernelIsa throws).
KernelIsa activeKernelIsa();

/// A kernel's per-level copies (see the top of this file); runKernel<&f> calls the active one.
template <auto Body>
struct Kernel;
template <class R, class... A, R (*Body)(A...)>
struct Kernel<Body> {
#if APERTURE_ISA_CLONES
  [[gnu::target("arch=x86-64-v4"), gnu::flatten, gnu::noinline]] static R v4(A... a) {
    return Body(static_cast<A>(a)...);
  }
  [[gnu::target("arch=x86-64-v3"), gnu::flatten, gnu::noinline]] static R v3(A... a) {
    return Body(static_cast<A>(a)...);
  }
#endif
  [[gnu::flatten, gnu::noinline]] static R baseline(A... a) { return Body(static_cast<A>(a)...); }

  static R run(A... a) {
#if APERTURE_ISA_CLONES
    switch (activeKernelIsa()) {
      case KernelIsa::V4:
        return v4(static_cast<A>(a)...);
      case KernelIsa::V3:
        return v3(static_cast<A>(a)...);
      case KernelIsa::Baseline:
        break;
    }
#endif
    return baseline(static_cast<A>(a)...);
  }
};

/// Calls kernel `Body` at the active level: runKernel<&renderTile<16, false>>(plan, ...).
template <auto Body, class... Args>
inline decltype(auto) runKernel(Args&&... args) {
  return Kernel<Body>::run(static_cast<Args&&>(args)...);
}

/// Whether x is finite, as a comparison that vectorises in a lane loop (std::isfinite does
/// not): false for ±inf and NaN.
template <class T>
inline bool finiteLane(T x) {
  return std::fabs(x) <= std::numeric_limits<T>::max();
}

}  // namespace aperture
