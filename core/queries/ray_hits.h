#pragma once
// Every surface along rays given by the caller (issue 44): the number of hits
// (count_intersections) and their list. Each ray is traced again just past its last hit
// (tnear moved to the next float after it) until it leaves the scene, so this works on any
// Scene, without the context filter the layers' one-traversal method needs
// (BuildOptions::contextFilter), and for any number of hits. countIntersections on a scene
// built with contextFilter traces each ray once, its filter recording every hit's t: the
// number of distinct t is what the retrace counts.
//
// What counts as a hit: each triangle Embree reports, once. Triangles hit at exactly the same
// float t as the previous hit are not reported again (a ray through the shared edge of two
// triangles, or coincident triangles, count once); a second triangle whose t rounds one float
// further would count again.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/engine/scene.h"

namespace aperture {

/// The hits of N rays as one list, ray by ray and nearest first: ray k's hits are
/// [offsets[k], offsets[k + 1]) (scipy's CSR layout).
struct RayHitList {
  std::vector<uint64_t> offsets;  ///< N + 1
  std::vector<double> t;          ///< distance along the ray, in units of |direction|
  std::vector<uint32_t> primId;   ///< the triangle, numbered as its mesh was loaded
  std::vector<uint32_t> geomId;   ///< the object (top-level geomID)
  size_t nonFinite = 0;           ///< rays not traced (not finite or beyond Embree's range)
};

/// `origins` and `directions`: 3 × count world coordinates; directions need not be unit
/// length. Rays whose origin or direction is not finite (or a zero direction) count 0 hits and
/// are counted in nonFinite. Every core is used.
std::vector<uint32_t> countIntersections(const Scene& scene, const double* origins,
                                         const double* directions, size_t count,
                                         size_t* nonFinite = nullptr);
RayHitList listIntersections(const Scene& scene, const double* origins, const double* directions,
                             size_t count);

}  // namespace aperture
