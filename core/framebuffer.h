#pragma once
// AOV (arbitrary output variable) framebuffers. Only requested AOVs are allocated.
#include <cstdint>
#include <string>
#include <vector>

namespace aperture {

/// One bit per AOV; a frame computes and stores only the bits it is asked for.
enum Aov : uint32_t {
  kAovColor = 1u << 0,     ///< R G B A: eye-light |N·D| shading, linear; A = coverage
  kAovDepth = 1u << 1,     ///< Z: planar depth along the view axis, scene units
  kAovDistance = 1u << 2,  ///< T: distance from the ray origin to the hit, scene units
  kAovNormal = 1u << 3,    ///< N.X N.Y N.Z: unit geometric normal, world space
  kAovPosition = 1u << 4,  ///< P.X P.Y P.Z: hit point, world space
  kAovPrimId = 1u << 5,    ///< primID (UINT)
  kAovGeomId = 1u << 6,    ///< geomID (UINT)
};
using AovMask = uint32_t;
inline constexpr uint32_t kInvalidId = 0xFFFFFFFFu;

/// Parses "color,depth,normal" (names: color depth distance normal position primid geomid,
/// or "all"). Throws Error naming the bad name and listing the valid ones.
AovMask parseAovList(const std::string& list);
/// The canonical comma-separated list for a mask, in the order above.
std::string aovListString(AovMask mask);

/// Per-pixel storage for the requested AOVs, row-major, row 0 at the top. Vectors of AOVs not
/// requested stay empty. Multi-channel AOVs are interleaved (rgba: 4 floats a pixel).
struct Framebuffer {
  int width = 0, height = 0;
  AovMask aovs = 0;
  std::vector<float> rgba;       ///< 4 per pixel
  std::vector<float> depth;      ///< Z, +inf on a miss
  std::vector<float> distance;   ///< T, +inf on a miss
  std::vector<float> normal;     ///< 3 per pixel, 0 on a miss
  std::vector<float> position;   ///< 3 per pixel, 0 on a miss
  std::vector<uint32_t> primId;  ///< kInvalidId on a miss
  std::vector<uint32_t> geomId;  ///< kInvalidId on a miss

  Framebuffer() = default;
  /// Allocates the requested AOVs, filled with their miss values.
  Framebuffer(int w, int h, AovMask mask);
  size_t pixelCount() const { return size_t(width) * size_t(height); }
  bool has(Aov a) const { return (aovs & a) != 0; }
};

}  // namespace aperture
