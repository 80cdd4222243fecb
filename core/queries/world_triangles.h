#pragma once
// The triangles of a Scene in world space and double precision, for the queries that read the
// triangles themselves (closedness, winding numbers) rather than trace rays.
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "core/engine/scene.h"

namespace aperture {

/// One object of a scene as its BVH holds it, placed in world space: its triangles (an object
/// built from a TriangleSubset has only the subset's) and where they stand in the scene's lists
/// of triangles and of vertices (worldObjects: objects in order, an object placed twice counted
/// twice).
struct WorldObject {
  const Mesh* mesh = nullptr;
  const uint32_t* indices = nullptr;  ///< 3 per triangle, into the mesh's vertices
  size_t triangles = 0;
  size_t firstTriangle = 0;  ///< the triangles of the objects before it
  size_t firstVertex = 0;    ///< the vertices of the meshes of the objects before it
  glm::dvec3 anchor{0.0};    ///< the mesh's
  glm::dmat4 worldFromMesh{1.0};

  /// The mesh's vertex v in world space: worldFromMesh · (mesh.anchor + position), in double.
  /// (A loop that stores doubles runs faster on a local copy of the object: the stores then
  /// cannot alias anchor and worldFromMesh, which need not be loaded again.)
  glm::dvec3 vertex(size_t v) const {
    return glm::dvec3(worldFromMesh * glm::dvec4(anchor + glm::dvec3(mesh->vertex(v)), 1.0));
  }
};

/// A scene's objects in order (WorldObject) and their totals.
struct WorldObjects {
  std::vector<WorldObject> objects;
  size_t triangles = 0;
  size_t vertices = 0;
};
WorldObjects worldObjects(const Scene& scene);

/// Three world-space corners per triangle (WorldObject::vertex), every object of the scene in
/// object order, each object's triangles in stored order; an object built from a
/// TriangleSubset gives only the subset's triangles (what its BVH holds). An object placed
/// twice gives its triangles twice.
std::vector<glm::dvec3> worldTriangleCorners(const Scene& scene);

}  // namespace aperture
