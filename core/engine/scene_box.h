#pragma once
// The box around everything a Scene can hit, and the lane test by which the frame loop resolves
// a ray that misses it as a miss without calling Embree. Where much of the image is background
// (a scan against an empty sky), most packets never reach Embree: an Embree call on a packet
// that misses everything still sets up its traversal (reciprocal directions, the root node),
// which costs more than this test (bench/RESULTS.md, "Issue 13, item 2: rays that miss the
// scene's box skip Embree").
//
// Conservative by construction, so images are bit-identical with and without it:
//  - the box is Embree's bounds of the committed scene (every vertex, instances placed), grown
//    by kSceneBoxPadding of its size and distance from the render origin, which covers how far
//    a hit Embree reports can lie from its triangle;
//  - the slab test moves each end of its interval outwards by kSlabSlack of its magnitude,
//    which covers the rounding of its three operations per axis (a subtraction, a reciprocal
//    and a product, each within 2^-24 relative);
//  - a lane whose test is undefined (NaN: an origin on a slab's plane with a direction parallel
//    to it) is kept.
#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <limits>
#include <optional>

#include "core/engine/camera.h"
#include "core/util/vector_kernel.h"

namespace aperture {

/// Axis-aligned box in render space.
struct SceneBox {
  glm::vec3 lo, hi;
};

/// Growth of the scene box, relative to the largest of its extent and its coordinates'
/// magnitude: 2^-14, far above the float rounding (2^-24) of the vertices and of Embree's hits.
inline constexpr float kSceneBoxPadding = 1.0f / 16384.0f;
/// Relative widening of each end of a ray's interval through the box: 2^-18, about twenty times
/// the worst rounding of the slab test's t (three operations of 2^-24 each).
inline constexpr float kSlabSlack = 1.0f / 262144.0f;

/// The box `lo`..`hi` (Embree's bounds of a committed scene) grown by kSceneBoxPadding; nullopt
/// when the bounds are not finite or empty (then no ray is resolved by the box).
inline std::optional<SceneBox> paddedSceneBox(const glm::vec3& lo, const glm::vec3& hi) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || lo[a] > hi[a]) return std::nullopt;
  const glm::vec3 extent = hi - lo, magnitude = glm::max(glm::abs(lo), glm::abs(hi));
  const float size =
      std::max({extent.x, extent.y, extent.z, magnitude.x, magnitude.y, magnitude.z});
  const float pad = kSceneBoxPadding * size + std::numeric_limits<float>::min();
  return SceneBox{lo - pad, hi + pad};
}

/// Whether `p` lies in `box`, faces included. A ray that starts there with tnear 0 always
/// reaches the box: maskLanesMissingBox keeps it.
inline bool boxContains(const SceneBox& box, const glm::vec3& p) {
  return glm::all(glm::lessThanEqual(box.lo, p)) && glm::all(glm::lessThanEqual(p, box.hi));
}

/// Clears valid[k] of every active lane whose ray, over [tnear, tfar], cannot reach `box`;
/// returns how many it cleared. Branch-free over the lanes (a lane loop: vector compares).
template <int N>
inline int maskLanesMissingBox(const SceneBox& box, const RayLanes& l, int* __restrict valid) {
  const glm::vec3 lo = box.lo, hi = box.hi;
  // Locals: the stores to valid[] could otherwise alias the lane pointers and force a reload
  // of each every lane (which kept the loop scalar).
  const float *ox = l.orgX, *oy = l.orgY, *oz = l.orgZ, *dx = l.dirX, *dy = l.dirY, *dz = l.dirZ;
  const float *tnear = l.tnear, *tfar = l.tfar;
  int cleared = 0;
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {
    const float ix = 1.0f / dx[k], iy = 1.0f / dy[k], iz = 1.0f / dz[k];
    const float ax = (lo.x - ox[k]) * ix, bx = (hi.x - ox[k]) * ix;
    const float ay = (lo.y - oy[k]) * iy, by = (hi.y - oy[k]) * iy;
    const float az = (lo.z - oz[k]) * iz, bz = (hi.z - oz[k]) * iz;
    const float enter = std::max(std::max(std::min(ax, bx), std::min(ay, by)),
                                 std::max(std::min(az, bz), tnear[k]));
    const float exit =
        std::min(std::min(std::max(ax, bx), std::max(ay, by)), std::min(std::max(az, bz), tfar[k]));
    // Each end moved outwards by the slack of its magnitude (a product, so an infinite end
    // stays infinite); a NaN end keeps the lane.
    const float early = enter * (enter > 0.0f ? 1.0f - kSlabSlack : 1.0f + kSlabSlack);
    const float late = exit * (exit > 0.0f ? 1.0f + kSlabSlack : 1.0f - kSlabSlack);
    const int misses = int(early > late);
    const int active = int(valid[k] != 0);
    cleared += active & misses;
    valid[k] = -(active & (misses ^ 1));
  }
  return cleared;
}

}  // namespace aperture
