#pragma once
// A mesh written back as binary little-endian PLY with per-face values: `aperture visibility
// --out OUT.ply` (view_count, best_view). MeshLab, Open3D and trimesh read it; so does
// aperture's loader (face properties as face.NAME).
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/ply.h"

namespace aperture {

/// One face property: one value per triangle of the mesh, of type UInt32 or Int32 (`values`
/// holds the 32-bit pattern; Int32 values are written as their two's complement).
struct PlyFaceProperty {
  std::string name;
  PlyType type = PlyType::UInt32;
  const uint32_t* values = nullptr;
};

/// Writes `mesh` to `path` (atomically): element vertex with double x, y, z (world: anchor +
/// position, summed in double), element face with `list uchar int vertex_indices` and then
/// `properties` in order. Faces are written in the order the mesh was loaded in (primID's),
/// which the properties' values follow. Throws Error naming the file for a property type other than
/// UInt32 or Int32, a bad property name, or an I/O failure.
void writePlyWithFaceProperties(const std::string& path, const Mesh& mesh,
                                const std::vector<PlyFaceProperty>& properties);

}  // namespace aperture
