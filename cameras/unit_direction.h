#pragma once
// A ray direction p / |p| in double, rounded to float, without a double square root or divide
// a ray, and bit for bit the float that the reference expression gives:
//   float(p.x * (1.0 / std::sqrt(|p|²)))   (PerspectiveCamera::rayAt, the golden ray hashes)
// The reciprocal length starts from float's square root and divide and takes two Newton steps
// in double (refinedInverseSqrt): within a few units in the last place of the reference's
// double, so the two round to the same float unless the value lies next to a float rounding
// point. unsureFloatRounding flags those lanes, and the caller computes them by the reference
// expression; it does for about one ray in a million. The argument is in docs/numerics.md,
// "Pinhole directions without a divide".
// Lane functions: branch-free, for loops the compiler vectorises (core/vector_kernel.h).
#include <cstdint>
#include <cstring>

namespace aperture {

/// Whether |p|² = len2 lies where refinedInverseSqrt holds its error bound: its float
/// conversion neither overflows nor leaves float's normal range. Outside, lanes are unsure.
inline bool inverseSqrtInRange(double len2) { return len2 >= 1e-30 && len2 <= 1e30; }

/// 1 / √len2 to a relative error within 4·2^-53: float's √ and ÷ (below 2^-22), then two
/// Newton steps r·(3/2 − (len2/2)·r²) in double, each of which squares the error.
/// Only for inverseSqrtInRange(len2).
inline double refinedInverseSqrt(double len2) {
  double r = double(1.0f / __builtin_sqrtf(float(len2)));
  const double half = 0.5 * len2;
  r = r * (1.5 - (half * r) * r);
  r = r * (1.5 - (half * r) * r);
  return r;
}

/// Units in the last place of a double within which unsureFloatRounding calls a value unsure:
/// eight times the at most 8 by which the two computations can differ (docs/numerics.md).
inline constexpr uint64_t kUnsureUlps = 64;

/// 1 where float(x) may differ from float(x') for an x' within kUnsureUlps units in the last
/// place of x: x lies that close to a midpoint between two floats (the 29 bits a double loses
/// in the conversion are that close to half of their range), or below float's normal range
/// (subnormals and flushing round elsewhere) and not zero. 0 otherwise.
inline uint64_t unsureFloatRounding(double x) {
  uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  constexpr uint64_t kDropped = (uint64_t(1) << 29) - 1, kHalf = uint64_t(1) << 28;
  const uint64_t nearMidpoint = ((bits & kDropped) - (kHalf - kUnsureUlps)) <= 2 * kUnsureUlps;
  const uint64_t exponent = (bits >> 52) & 0x7FF;
  const uint64_t belowFloatNormals = (exponent < 1023 - 126) & ((bits << 1) != 0);
  return nearMidpoint | belowFloatNormals;
}

}  // namespace aperture
