#pragma once
// A small glTF 2.0 writer for tests, independent of the loader (core/mesh/gltf*.cpp): describe
// a scene (meshes of primitives, nodes, materials, cameras) as plain structs, then write it as
// .gltf + .bin, as .glb, and with its triangles Draco- or meshopt-compressed.
//
//   GltfScene s;
//   s.meshes.push_back({"tri", {{/*positions*/ {0,0,0, 1,0,0, 0,1,0}}}});
//   s.nodes.push_back({"n"});  s.nodes[0].mesh = 0;  s.roots = {0};
//   writeGltf(s, dir + "/tri.glb");
#include <cstdint>
#include <cstring>
#include <functional>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace aperture::test {

/// One primitive. Attributes are float32; empty vectors are left out of the file.
struct GltfPrimitive {
  std::vector<float> positions;   ///< 3 per vertex
  std::vector<uint32_t> indices;  ///< empty: not indexed (written as unsigned int)
  std::vector<float> normals;     ///< 3 per vertex or empty
  std::vector<float> uv;          ///< 2 per vertex (TEXCOORD_0) or empty
  std::vector<float> colors;      ///< 4 per vertex (COLOR_0, linear RGBA) or empty
  int material = -1;              ///< -1: none
  int mode = 4;                   ///< 0-6 (4 triangles, 5 strip, 6 fan)
};

struct GltfMesh {
  std::string name;  ///< "" leaves `name` out
  std::vector<GltfPrimitive> primitives;
};

/// A node: either `matrix` or any of translation / rotation / scale (or none).
struct GltfNode {
  std::string name;  ///< "" leaves `name` out
  int mesh = -1, camera = -1;
  std::vector<int> children;
  std::optional<glm::dmat4> matrix;
  std::optional<glm::dvec3> translation;
  std::optional<glm::dquat> rotation;  ///< written as (x, y, z, w)
  std::optional<glm::dvec3> scale;
};

/// A node's local transform as glTF 2.0 defines it (its matrix, else T · R · S), composed with
/// glm's own functions: the tests' reference, independent of the loader.
inline glm::dmat4 gltfLocalMatrix(const GltfNode& n) {
  if (n.matrix) return *n.matrix;
  glm::dmat4 m(1.0);
  if (n.translation) m = glm::translate(m, *n.translation);
  if (n.rotation) m = m * glm::mat4_cast(*n.rotation);
  if (n.scale) m = glm::scale(m, *n.scale);
  return m;
}

struct GltfMaterial {
  std::string name;  ///< "" leaves `name` out
  glm::vec4 baseColor{1.0f};
  /// A base colour texture, when either is set: PNG bytes (embedded in the binary buffer, or
  /// written beside the file when `externalImage`), or a uri written as is (not checked).
  std::vector<unsigned char> png;
  bool externalImage = false;
  std::string imageUri;
  int texCoord = 0;
  int wrapS = 10497, wrapT = 10497;  ///< sampler wrap modes (REPEAT)
  int magFilter = -1;                ///< -1: absent; 9728 NEAREST, 9729 LINEAR
};

struct GltfCamera {
  bool orthographic = false;
  double yfov = 0.8, aspectRatio = 0, znear = 0.1, zfar = 0;  ///< 0: absent (aspect, zfar)
  double xmag = 1, ymag = 1;
};

struct GltfScene {
  std::vector<GltfMesh> meshes;
  std::vector<GltfNode> nodes;
  std::vector<GltfMaterial> materials;
  std::vector<GltfCamera> cameras;
  std::vector<int> roots;  ///< the nodes of scene 0 (the file's only scene)
  std::vector<std::string> extensionsRequired;
};

enum class GltfCompression {
  None,
  Draco,    ///< triangle primitives (mode 4) Draco-encoded, sequential, no quantization
  Meshopt,  ///< every attribute and index view meshopt-encoded; the fallback buffer is empty
};

/// Writes `scene` to `path`: a .glb container, or a .gltf with its data in "<stem>.bin" beside
/// it. Returns `path`.
std::string writeGltf(const GltfScene& scene, const std::string& path,
                      GltfCompression compression = GltfCompression::None);
/// The JSON of a written .gltf, edited by `edit` and written back (bad-input tests).
void editGltf(const std::string& path, const std::function<void(nlohmann::json&)>& edit);

/// `bytes` as a base64 data URI ("data:application/octet-stream;base64,...").
std::string dataUri(const std::vector<unsigned char>& bytes);

/// The bytes of `values` (little-endian, as the machine stores them).
template <class T>
std::vector<unsigned char> gltfBytes(const std::vector<T>& values) {
  std::vector<unsigned char> out(values.size() * sizeof(T));
  if (!out.empty()) std::memcpy(out.data(), values.data(), out.size());
  return out;
}

/// A glTF written by hand, for layouts the writer above does not produce (integer and
/// normalized attributes, strides, sparse accessors): add buffer views of raw bytes, write the
/// rest of `doc` (accessors, meshes, nodes, scenes) directly, then write() it as one .gltf with
/// its buffer in a data URI.
struct RawGltf {
  nlohmann::json doc = nlohmann::json::object();
  std::vector<unsigned char> bin;
  /// Appends `bytes` (4-byte aligned) as buffer view; byteStride when `stride` > 0.
  int addView(const std::vector<unsigned char>& bytes, int stride = 0);
  /// Appends an accessor; `view` < 0 leaves bufferView out.
  int addAccessor(int view, int componentType, const std::string& type, size_t count,
                  bool normalized = false, size_t byteOffset = 0);
  /// One mesh of one primitive placed by one node in scene 0 (attributes: name -> accessor).
  void addMeshNode(const nlohmann::json& attributes, int indices = -1, int mode = 4);
  /// Writes `path` (asset and buffer 0 added: buffers already in doc["buffers"] follow it, so
  /// theirs are indices 1, 2, ...); returns it.
  std::string write(const std::string& path) const;
};

/// An RGB PNG of `size` x `size` pixels: a checkerboard of `cells` x `cells` squares, black at
/// the top-left, white beside it (zlib-compressed, written here with zlib only).
std::vector<unsigned char> checkerPng(int size, int cells);

/// The issue 41 test scene: nested nodes with TRS and matrix transforms, mesh 0 (a textured
/// quad with vertex colours, material 0 "checker": the 8 x 8 checkerboard of 2 x 2 cells)
/// placed by three nodes, mesh 1 (one red triangle, material 1 "red", baseColor (1, 0, 0, 1))
/// placed once, and a perspective camera node. Nodes: 0 "root" (TRS) -> 1 "quad_a" (T),
/// 2 "quad_b" (matrix), 3 "group" (R) -> 4 "quad_c" (S), 5 "tri" (T); 6 "camera" (T).
GltfScene issue41Scene();

}  // namespace aperture::test
