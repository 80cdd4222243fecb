#pragma once
// Deterministic sample positions: every value is a pure function of (pixel, sample index,
// dimension), never of the thread or tile, so images do not depend on scheduling.
#include <cmath>
#include <cstdint>

namespace aperture {

/// 32-bit integer hash (lowbias32 by Chris Wellons' hash-prospector); full avalanche.
inline uint32_t hash32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

/// Uniform double in [0, 1) from (pixel x, pixel y, sample, dimension).
inline double sampleUniform(uint32_t px, uint32_t py, uint32_t sample, uint32_t dim) {
  uint32_t h = hash32(px ^ hash32(py ^ hash32(sample ^ hash32(dim * 0x9e3779b9U))));
  return double(h) * (1.0 / 4294967296.0);
}

/// Strata grid for n samples: nx * ny >= n with nx = ceil(sqrt(n)), ny = ceil(n / nx).
inline void strataGrid(int n, int& nx, int& ny) {
  nx = int(std::ceil(std::sqrt(double(n))));
  ny = (n + nx - 1) / nx;
}

/// Stratified 2-D sample s of n in [0,1)^2 for pixel (px, py) and dimension pair `dim`:
/// sample s falls in stratum (s % nx, s / nx), jittered within it. For n == 1 the result is
/// exactly (0.5, 0.5), so one sample per pixel means pixel centres.
inline void stratified2D(uint32_t px, uint32_t py, int s, int n, uint32_t dim, double& x,
                         double& y) {
  if (n == 1) {
    x = 0.5;
    y = 0.5;
    return;
  }
  int nx, ny;
  strataGrid(n, nx, ny);
  const int sx = s % nx, sy = s / nx;
  x = (sx + sampleUniform(px, py, uint32_t(s), 2 * dim)) / nx;
  y = (sy + sampleUniform(px, py, uint32_t(s), 2 * dim + 1)) / ny;
}

}  // namespace aperture
