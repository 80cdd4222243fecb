#pragma once
// The triangles of a Scene in world space and double precision, for the queries that read the
// triangles themselves (closedness, winding numbers) rather than trace rays.
#include <cstddef>
#include <glm/glm.hpp>
#include <vector>

#include "core/engine/scene.h"

namespace aperture {

/// Three world-space corners per triangle (x = worldFromMesh · (mesh.anchor + position), in
/// double), every object of the scene in object order, each object's triangles in stored
/// order; an object built from a TriangleSubset gives only the subset's triangles (what its
/// BVH holds). An object placed twice gives its triangles twice.
std::vector<glm::dvec3> worldTriangleCorners(const Scene& scene);

}  // namespace aperture
