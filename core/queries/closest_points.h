#pragma once
// The closest point of a scene's surface to each of N world points (issue 44): Embree's point
// query (rtcPointQuery) walks the BVH, and each candidate triangle's closest point is computed
// in double precision from the world positions, worldFromMesh · (anchor + position), so the
// distance is exact to double rounding whatever the render origin and the instance transforms.
// Directly attached, instanced and chunked objects all report in the scene's terms: the object
// (top-level geomID), the triangle as loaded (Scene::sourcePrimId) and the instance id.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/engine/scene.h"

namespace aperture {

/// What closestPoints reports per query point. Points that are not finite (or too large for
/// Embree's float query, beyond kEmbreeLargest) get NaN coordinates, distance and barycentric
/// weights and kNoPrim ids; they are counted in nonFinite.
struct ClosestPoints {
  static constexpr uint32_t kNoPrim = 0xFFFFFFFFu;
  std::vector<double> points;       ///< 3 per query: the closest surface point, world space
  std::vector<double> distance;     ///< 1 per query: |query − point|
  std::vector<double> barycentric;  ///< 3 per query: the weights of the triangle's corners
  std::vector<uint32_t> primId;     ///< the triangle, numbered as its mesh was loaded
  std::vector<uint32_t> geomId;     ///< the object (top-level geomID, the AOVs' geomID)
  std::vector<uint32_t> instance;   ///< the instance id (ObjectIds::instance + OBJ face group)
  size_t nonFinite = 0;
};

/// The closest surface point of `scene` to each of the `count` world points in `points`
/// (x, y, z per point), on every core. Among triangles at the same distance, the one of the
/// lowest (object, primId) wins, so chunked, instanced and whole builds of one mesh agree.
/// Throws Error when the scene holds no triangle.
ClosestPoints closestPoints(const Scene& scene, const double* points, size_t count);

/// The closest point of triangle (a, b, c) to p, in double, with its barycentric weights
/// (wa, wb, wc), summing to 1; a degenerate triangle gives the closest point of its edges.
struct TrianglePoint {
  double x, y, z;
  double wa, wb, wc;
};
TrianglePoint closestPointOnTriangle(const double* p, const double* a, const double* b,
                                     const double* c);

}  // namespace aperture
