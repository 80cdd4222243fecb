#pragma once
// Helpers of the EXR and atomic-write tests (tests/core/exr/test_exr.cpp,
// tests/core/io/test_atomic_file.cpp): a framebuffer with every AOV patterned, a file's bytes, a
// directory's names.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/aov/framebuffer.h"

namespace aperture::test {

/// The AOVs patterned() fills: all of them.
inline constexpr AovMask kAllAovs =
    kAovColor | kAovDepth | kAovDistance | kAovNormal | kAovPosition | kAovPrimId | kAovGeomId;

/// Every AOV filled with distinct values; every 5th pixel is a miss (+inf, invalid ids).
inline Framebuffer patterned(int w, int h) {
  const float kInf = std::numeric_limits<float>::infinity();
  Framebuffer fb(w, h, kAllAovs);
  for (size_t i = 0; i < fb.pixelCount(); ++i) {
    const float f = float(i);
    for (int c = 0; c < 4; ++c) fb.rgba[4 * i + c] = 0.013f * f + 0.21f * float(c) + 0.001f;
    for (int c = 0; c < 3; ++c) {
      fb.normal[3 * i + c] = std::sin(0.7f * f + float(c));
      fb.position[3 * i + c] = -3.3f + 0.117f * f * float(c + 1);
    }
    if (i % 5 == 0) {
      fb.depth[i] = fb.distance[i] = kInf;
      fb.primId[i] = fb.geomId[i] = kInvalidId;
    } else {
      fb.depth[i] = 1.5f + 0.37f * f;
      fb.distance[i] = 1.7f + 0.41f * f;
      fb.primId[i] = uint32_t(1000003u * i + 7u);
      fb.geomId[i] = uint32_t(i % 3);
    }
  }
  return fb;
}

/// The whole content of a file, binary ("" when it cannot be read).
inline std::string readBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// The names in a directory, sorted.
inline std::vector<std::string> listDir(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace aperture::test
