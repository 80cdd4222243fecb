#pragma once
// View-volume culling: keep only the triangles a set of cameras may see, so the BVH holds
// what the frames need. The test is conservative (a triangle is dropped only when its
// bounding box is certainly outside every volume), so images do not change.
#include <cstddef>
#include <deque>
#include <functional>
#include <glm/glm.hpp>
#include <vector>

#include "core/engine/scene.h"

namespace aperture {

/// False only when the world-space box [lo, hi] is certainly not seen.
using WorldBoxTest = std::function<bool(const glm::dvec3& lo, const glm::dvec3& hi)>;

/// Triangles are tested in clusters of this many consecutive ones (one box each) first;
/// the triangles of a cluster that may be seen are then tested one by one.
inline constexpr size_t kCullClusterSize = 64;

struct CullStats {
  size_t trianglesBefore = 0;  ///< over the distinct meshes
  size_t trianglesKept = 0;
  size_t clustersTested = 0;  ///< clusters of kCullClusterSize triangles
  double seconds = 0;         ///< wall time of the culling pass
  size_t subsetBytes = 0;     ///< memory of the culled index and primID buffers
};

/// The triangles of `mesh` whose box, in at least one of `placements` (world from mesh), may
/// pass `test`, in their original order. Parallel over clusters (TBB).
TriangleSubset cullTriangles(const Mesh& mesh, const std::vector<glm::dmat4>& placements,
                             const WorldBoxTest& test);

/// Culls every distinct mesh of `objects` against `test` (all of a mesh's placements count)
/// and points each object's `subset` at its mesh's result, stored in `storage` (which must
/// outlive the Scene built from the objects).
CullStats cullObjects(std::vector<SceneObject>& objects, const WorldBoxTest& test,
                      std::deque<TriangleSubset>& storage);

}  // namespace aperture
