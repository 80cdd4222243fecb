#pragma once
// Triangle meshes as loaded from PLY, OBJ or a procedural generator.
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/aov/framebuffer.h"
#include "core/util/huge_pages.h"

namespace aperture {

/// Embree reads up to 16 bytes at the address of the last vertex; positions carry this many
/// zero floats after the last xyz triple so the buffer can be shared with Embree as is.
inline constexpr size_t kVertexPaddingFloats = 4;

/// What the loader saw, reported to the user and in bench output.
struct MeshStats {
  size_t fileBytes = 0;            ///< bytes of the source file (0 for procedural meshes)
  double loadSeconds = 0;          ///< wall time of loadMesh
  size_t sourceFaces = 0;          ///< faces/strips/polygons in the file before triangulation
  size_t nonFiniteVertices = 0;    ///< vertices with a NaN or Inf coordinate (set to 0)
  size_t droppedTriangles = 0;     ///< triangles dropped because they use a non-finite vertex
  size_t degenerateTriangles = 0;  ///< triangles with a repeated index (kept; Embree skips them)
};

/// An integer property of faces or vertices (PLY), kept only when LoadOptions asks for it.
/// Signed values are stored as their 32-bit two's complement (-1 becomes 0xFFFFFFFF, the
/// value of a miss: documented for labels that use -1 as "none").
struct MeshProperty {
  PropertyDomain domain = PropertyDomain::Face;
  std::string name;
  /// Face domain: one value per triangle (after triangulation: a polygon's value on each of
  /// its triangles, and dropped with a dropped triangle). Vertex domain: one per vertex.
  std::vector<uint32_t> values;
};

/// An indexed triangle mesh. World position of vertex k is anchor + positions[3k..3k+2].
/// The anchor is chosen at load (the bounding-box centre in camera-relative mode, the origin
/// in world-space mode) and kept in double so far-from-origin meshes keep float precision.
struct Mesh {
  std::string name;        ///< file path or procedural spec it came from
  glm::dvec3 anchor{0.0};  ///< world-space origin of `positions`, scene units
  /// 3 * vertexCount floats, then kVertexPaddingFloats zeros. A LargeBuffer, as are the
  /// indices: the loaders size them without writing them, then fill them in parallel.
  LargeBuffer<float> positions;
  LargeBuffer<uint32_t> indices;  ///< 3 per triangle, each < vertexCount
  size_t vertexCount = 0;
  /// Optional: loaders of double-precision sources (PLY double properties, procedural scenes)
  /// fill this instead of `positions`; finishMesh() anchors it in double and clears it.
  std::vector<double> positionsDouble;
  /// Per-vertex normals (3 per vertex, as in the file, not normalised), only when
  /// LoadOptions::vertexNormals and the file has them (PLY nx ny nz, OBJ vn); else empty.
  /// Transformed with the positions (by the inverse transpose) in finishMesh.
  std::vector<float> vertexNormals;
  /// The integer properties LoadOptions::properties asked for, in that order.
  std::vector<MeshProperty> properties;
  /// Surface attributes per vertex, kept only when LoadOptions asks (texcoords,
  /// vertexColors) and the source has them; else empty. Not transformed by finishMesh.
  std::vector<float> texcoords;     ///< 2 per vertex: glTF TEXCOORD_0 as stored, OBJ vt
  std::vector<float> vertexColors;  ///< 4 per vertex: glTF COLOR_0 as linear RGBA (RGB: A = 1)
  /// Per triangle, moved and dropped with the triangles (forEachFaceArray), kept only when
  /// LoadOptions asks (materials, groups); empty: every triangle has value 0.
  std::vector<uint32_t> faceMaterials;  ///< index into the source's materials (SceneFile)
  std::vector<uint32_t> faceGroups;     ///< OBJ: the object (o/g) of each triangle
  /// Empty while the triangles are in the order they were loaded in (the order primID
  /// numbers them by). After orderTrianglesInSpace (core/engine/triangle_order.h) moved them, the
  /// loaded index of each stored triangle: primID outputs go through sourceTriangle().
  std::vector<uint32_t> sourceTriangles;
  MeshStats stats;

  size_t triangleCount() const { return indices.size() / 3; }
  /// The index in the loaded order (what primID reports) of stored triangle `t`.
  uint32_t sourceTriangle(size_t t) const {
    return sourceTriangles.empty() ? uint32_t(t) : sourceTriangles[t];
  }
  glm::vec3 vertex(size_t k) const {
    return {positions[3 * k], positions[3 * k + 1], positions[3 * k + 2]};
  }
  /// The property of `domain` named `name`, or nullptr.
  const MeshProperty* property(PropertyDomain domain, const std::string& propertyName) const;
  /// Bounds of the finite vertices relative to the anchor; empty mesh gives min > max.
  void bounds(glm::vec3& lo, glm::vec3& hi) const;
};

/// Calls `f` on every per-triangle array of `mesh` that is not empty (face properties,
/// faceMaterials, faceGroups): whatever moves or drops triangles moves or drops these with them.
template <class F>
void forEachFaceArray(Mesh& mesh, F&& f) {
  for (MeshProperty& p : mesh.properties)
    if (p.domain == PropertyDomain::Face) f(p.values);
  if (!mesh.faceMaterials.empty()) f(mesh.faceMaterials);
  if (!mesh.faceGroups.empty()) f(mesh.faceGroups);
}

/// Bytes the mesh's buffers hold (capacities: what is allocated, not only what is used):
/// positions, indices, vertex normals, properties, the source order of reordered triangles
/// and any loader-only double positions.
size_t meshBufferBytes(const Mesh& mesh);

/// How coordinates are stored.
enum class Placement {
  CameraRelative,  ///< anchor = bounding-box centre (computed in double); default
  WorldSpace,      ///< anchor = origin: float32 world coordinates, for measuring the difference
};

struct LoadOptions {
  Placement placement = Placement::CameraRelative;
  /// Applied in double to every vertex before anchoring (x' = scale * x + translate).
  glm::dvec3 translate{0.0};
  double scale = 1.0;
  /// Optional placement applied in double after scale and translate:
  /// x' = transform · (scale * x + translate, 1). Must be affine (last row 0 0 0 1).
  std::optional<glm::dmat4> transform;
  /// Integer face/vertex properties to keep (requested AOVs "face.NAME", "vertex.NAME").
  /// A name the file does not have is an Error naming the file and listing the integer
  /// properties it has; a procedural mesh or an OBJ has none. Nothing is stored unasked.
  std::vector<PropertyAov> properties;
  /// Keep per-vertex normals when the file has them (the shading-normal AOV asks for them).
  bool vertexNormals = false;
  /// Surface data the AOVs ask for (app::withAovNeeds): texture coordinates (uv, albedo),
  /// vertex colours (vertex-color, albedo), per-triangle materials (material, albedo) and OBJ
  /// objects (instance). Nothing is stored unasked.
  bool texcoords = false, vertexColors = false, materials = false, groups = false;
  /// glTF: the index of the scene to load (--gltf-scene); unset: the file's `scene`, else 0.
  std::optional<int> gltfScene;
  /// PLY only: read the vertex element alone, as a point set (`--points P.ply`): a file
  /// without faces is accepted and face or tristrips elements are skipped, so the mesh may
  /// have no triangles.
  bool verticesOnly = false;
};

/// Loads `spec`: a path ending in .ply or .obj (case-insensitive), or "procedural:NAME?k=v&k=v"
/// (see procedural.cpp for the names). Throws Error naming the file and the problem: unreadable,
/// truncated, bad number, counts larger than the file, an index out of range.
Mesh loadMesh(const std::string& spec, const LoadOptions& options = {});
/// The loader's mesh of `spec` (PLY, OBJ as one mesh, procedural) before finishMesh: what
/// loadMesh finishes and a scene file of one mesh places (core/mesh/scene_file.h).
Mesh loadUnfinishedMesh(const std::string& spec, const LoadOptions& options = {});

/// Loaders for one format each (loadMesh dispatches). They fill positions in world space
/// (anchor 0, no padding); finishMesh() then validates, anchors and pads. Of `options` they
/// read only what to keep beyond positions and indices: `properties` and `vertexNormals`
/// (PLY, OBJ), `texcoords`, `groups` and `materials` (OBJ).
/// OBJ: no integer properties (a request is an Error); normals from `vn` and texture
/// coordinates from `vt` (stored as (u, 1 - v): (0, 0) is the image's top-left) through the
/// corners' indices, a vertex used with several (vt, vn) pairs split into one vertex per pair
/// (so vertexCount may grow; triangles keep their order and so their primIDs); a face corner
/// without a normal (texture) index in a file whose other corners have one is an Error.
/// faceGroups: the object (`o`/`g`) of each triangle, faceMaterials: its `usemtl` material,
/// ids in order of first appearance (see loadObjScene in scene_file.h for the names, the
/// default object and material, and the .mtl files, which loadObj does not read).
Mesh loadPly(const std::string& path, const LoadOptions& options = {});
Mesh loadObj(const std::string& path, const LoadOptions& options = {});
/// The same on a file already in memory (`size` bytes at `data`, which need not be aligned or
/// terminated); `name` stands for the file in messages. Used by the fuzz targets.
Mesh loadPlyFromMemory(const char* data, size_t size, const std::string& name,
                       const LoadOptions& options = {});
Mesh loadObjFromMemory(const char* data, size_t size, const std::string& name,
                       const LoadOptions& options = {});
Mesh makeProcedural(const std::string& spec);

/// How many vertices and triangles a mesh has.
struct MeshCounts {
  size_t vertices = 0;
  size_t triangles = 0;
};
/// The counts makeProcedural(spec) will have, from the generator's own layout and without
/// generating the large meshes (used by the memory estimate). Throws Error for a bad spec,
/// as makeProcedural does.
MeshCounts proceduralMeshCounts(const std::string& spec);

/// The extension of the last path component, lower-cased with its dot (".ply"), or "".
std::string lowerExtension(const std::string& path);

/// Counts and zeroes non-finite vertices, drops the triangles using them (and their face
/// property values), counts degenerate triangles, checks every index (< vertexCount, else
/// Error naming `name`), applies the options' transform and anchor, and pads positions for
/// Embree. Vertex normals go through the inverse transpose of the linear part of
/// x -> transform · (scale * x + translate): a mirroring placement (negative scale or
/// determinant) keeps them pointing out of the same side of the surface.
void finishMesh(Mesh& mesh, const LoadOptions& options);

}  // namespace aperture
