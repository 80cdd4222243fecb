#pragma once
// Triangles moved along a space-filling curve, so that a large mesh stored in an order
// scattered in space (by part, material or scan) can still be built in chunks
// (BuildOptions::bvhChunkTriangles), whose build holds one chunk's primitive references at a
// time. The loaded order stays what primID reports: Mesh::sourceTriangles maps back.
#include <cstdint>
#include <vector>

#include "core/engine/scene.h"
#include "core/mesh/mesh.h"

namespace aperture {

/// Moves the triangles of `mesh` into the Morton order of the cells of a 32³ grid on the
/// mesh's box that hold their centroids (stable: triangles of one cell keep their order; a
/// non-finite centroid sorts last). Indices and face properties move with their triangles;
/// mesh.sourceTriangles gets each triangle's loaded index (composed with an earlier move).
void orderTrianglesInSpace(Mesh& mesh);

/// orderTrianglesInSpace, when `options` would otherwise build `mesh`, attached directly, as
/// one BVH only because of its triangle order: it has more triangles than the options' chunk,
/// and its chunksPerCell is above BuildOptions::maxChunksPerCell. One pass over the centroids
/// serves both the decision and the order. Returns whether the triangles moved.
bool orderIfScattered(Mesh& mesh, const BuildOptions& options);

/// The stored triangle of each loaded index (the inverse of mesh.sourceTriangles); empty when
/// the triangles are in their loaded order.
std::vector<uint32_t> storedTriangles(const Mesh& mesh);

}  // namespace aperture
