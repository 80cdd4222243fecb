// A mesh with per-face values as binary little-endian PLY (Greg Turk's format, as the loader in
// core/mesh/ply.cpp reads it). The type names are PLY's original ones ("double", "uchar", "int",
// "uint"): every reader knows those, while the sized aliases ("float64", "uint32") are a later
// addition some readers lack. Faces are the mesh's triangles in order, so face k of the file is
// primID k of a render.
#include "core/io/ply_writer.h"

#include <climits>
#include <cstring>
#include <set>

#include "core/engine/triangle_order.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"
#include "core/util/little_endian.h"

namespace aperture {

namespace {

const char* plyTypeName(PlyType type) { return type == PlyType::Int32 ? "int" : "uint"; }

/// A property name a PLY header line can hold and the readers will not confuse with the
/// indices: printable ASCII without spaces.
bool isPlainName(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name)
    if (c < 0x21 || c > 0x7e) return false;
  return true;
}

void checkProperties(const std::string& path, const Mesh& mesh,
                     const std::vector<PlyFaceProperty>& properties) {
  std::set<std::string> names = {"vertex_indices"};
  for (const PlyFaceProperty& p : properties) {
    if (p.type != PlyType::UInt32 && p.type != PlyType::Int32)
      throw Error(cat("cannot write '", path, "': face property '", p.name,
                      "' has a type other than UInt32 or Int32"));
    if (!isPlainName(p.name))
      throw Error(cat("cannot write '", path, "': face property name '", p.name,
                      "' is empty or holds spaces or non-ASCII bytes"));
    if (!names.insert(p.name).second)
      throw Error(cat("cannot write '", path, "': face property '", p.name,
                      "' is given twice or is the indices' name"));
    if (!p.values && mesh.triangleCount() > 0)
      throw Error(cat("cannot write '", path, "': face property '", p.name, "' has no values"));
  }
}

std::string headerText(const Mesh& mesh, const std::vector<PlyFaceProperty>& properties) {
  std::string h =
      cat("ply\nformat binary_little_endian 1.0\n",
          "comment aperture: vertices in world coordinates\n", "element vertex ", mesh.vertexCount,
          "\nproperty double x\nproperty double y\nproperty double z\n", "element face ",
          mesh.triangleCount(), "\nproperty list uchar int vertex_indices\n");
  for (const PlyFaceProperty& p : properties)
    h += cat("property ", plyTypeName(p.type), " ", p.name, "\n");
  return h + "end_header\n";
}

/// World position of vertex k, coordinate a: anchor + position, summed in double. A mesh not
/// yet through finishMesh may still hold its positions in double.
double worldCoordinate(const Mesh& mesh, size_t k, int a) {
  const double local = mesh.positionsDouble.empty() ? double(mesh.positions[3 * k + size_t(a)])
                                                    : mesh.positionsDouble[3 * k + size_t(a)];
  return mesh.anchor[a] + local;
}

}  // namespace

void writePlyWithFaceProperties(const std::string& path, const Mesh& mesh,
                                const std::vector<PlyFaceProperty>& properties) {
  checkProperties(path, mesh, properties);
  const size_t stored =
      mesh.positionsDouble.empty() ? mesh.positions.size() : mesh.positionsDouble.size();
  if (stored < 3 * mesh.vertexCount)
    throw Error(cat("cannot write '", path, "': the mesh holds ", stored, " coordinates for ",
                    mesh.vertexCount, " vertices"));
  if (mesh.vertexCount > size_t(INT_MAX))
    throw Error(cat("cannot write '", path, "': ", mesh.vertexCount,
                    " vertices is more than PLY's int indices can address"));
  const std::string header = headerText(mesh, properties);
  std::vector<char> vertices;
  vertices.reserve(24 * mesh.vertexCount);
  for (size_t k = 0; k < mesh.vertexCount; ++k)
    for (int a = 0; a < 3; ++a) appendLittleEndian(vertices, worldCoordinate(mesh, k, a));
  std::vector<char> faces;
  const size_t triangles = mesh.triangleCount();
  faces.reserve(triangles * (1 + 12 + 4 * properties.size()));
  const std::vector<uint32_t> storedAt = storedTriangles(mesh);
  for (size_t f = 0; f < triangles; ++f) {  // in the loaded order, as the properties are
    const size_t t = storedAt.empty() ? f : storedAt[f];
    appendLittleEndian<uint8_t>(faces, 3);
    for (int c = 0; c < 3; ++c) appendLittleEndian(faces, int32_t(mesh.indices[3 * t + size_t(c)]));
    // Int32 values are given as their two's complement bit pattern: the same four bytes.
    for (const PlyFaceProperty& p : properties) appendLittleEndian(faces, p.values[f]);
  }
  writePiecesAtomically(path, {{header.data(), header.size()},
                               {vertices.data(), vertices.size()},
                               {faces.data(), faces.size()}});
}

}  // namespace aperture
