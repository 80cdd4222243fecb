// The divider floor of the pinhole rays (issue 13, item 1): the golden ray hashes
// (tests/cameras/models/test_golden.cpp) hold every pinhole direction to p · (1 / sqrt(|p|²)) in
// double, rounded once to float, so each ray costs one double square root and one double
// divide. This loop runs only those two instructions, on independent data, 16 rays (two
// 8-wide vectors) per iteration, and prints the time per ray: the least any ray generation
// that computes the golden rays this way can cost on this CPU (the exact alternatives tried,
// first guesses refined in double with a fallback, were slower: bench/RESULTS.md). Not part of
// the build (it needs AVX-512):
//
//   g++ -O2 -mavx512f bench/divider_floor.cpp -o /tmp/divider_floor && /tmp/divider_floor
#include <immintrin.h>

#include <chrono>
#include <cstdio>

int main() {
  constexpr long kPackets = 50'000'000;
  __m512d a = _mm512_set1_pd(2.0), b = _mm512_set1_pd(3.0);
  const __m512d one = _mm512_set1_pd(1.0), step = _mm512_set1_pd(1e-9);
  __m512d sumA = _mm512_setzero_pd(), sumB = _mm512_setzero_pd();
  const auto start = std::chrono::steady_clock::now();
  for (long k = 0; k < kPackets; ++k) {
    a = _mm512_add_pd(a, step);
    b = _mm512_add_pd(b, step);
    sumA = _mm512_add_pd(sumA, _mm512_div_pd(one, _mm512_sqrt_pd(a)));
    sumB = _mm512_add_pd(sumB, _mm512_div_pd(one, _mm512_sqrt_pd(b)));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double nsPerRay = seconds / (double(kPackets) * 16) * 1e9;
  alignas(64) double sums[8];
  _mm512_store_pd(sums, _mm512_add_pd(sumA, sumB));
  std::printf("double 1/sqrt: %.3f ns/ray on one thread, %.3f ns/ray on two cores (checksum %g)\n",
              nsPerRay, nsPerRay / 2, sums[0]);
  return 0;
}
