// glTF accessors: integer attributes (KHR_mesh_quantization), normalized integers against the
// spec's formulas (glTF 2.0, 3.11), byteStride, sparse accessors, index types; and the
// triangulation of strips and fans against hand-written index lists.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/mesh/scene_file.h"
#include "core/util/error.h"
#include "tests/gltf_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::gltfBytes;
using test::RawGltf;

LoadOptions gltfAccessorOptions() {
  LoadOptions o;
  o.vertexNormals = o.texcoords = o.vertexColors = o.materials = true;
  return o;
}

/// Interleaves `values` (`components` per element of type T) into elements of `stride` bytes.
template <class T>
std::vector<unsigned char> gltfStrided(const std::vector<T>& values, int components, int stride) {
  const size_t n = values.size() / size_t(components);
  std::vector<unsigned char> out(n * size_t(stride), 0xAB);
  for (size_t i = 0; i < n; ++i)
    std::memcpy(&out[i * size_t(stride)], &values[i * size_t(components)],
                sizeof(T) * size_t(components));
  return out;
}

TEST(GltfAccessors, QuantizedAndNormalizedAttributes) {
  RawGltf g;
  const std::vector<int16_t> pos = {-3, 7, 100, 1, 2, 3, 32767, -32768, 0};
  const std::vector<int8_t> nrm = {127, 0, -128, 0, -127, 64, 10, 20, -30};
  const std::vector<uint16_t> uv = {0, 65535, 32768, 1, 65535, 0};
  const std::vector<uint8_t> col = {255, 0, 128, 1, 2, 3, 0, 255, 64};
  const std::vector<uint8_t> idx = {0, 1, 2};
  // Positions: SHORT, not normalized, stride 8 (6 bytes and 2 of padding).
  const int p = g.addAccessor(g.addView(gltfStrided(pos, 3, 8), 8), 5122, "VEC3", 3);
  const int n = g.addAccessor(g.addView(gltfStrided(nrm, 3, 4), 4), 5120, "VEC3", 3, true);
  const int t = g.addAccessor(g.addView(gltfBytes(uv)), 5123, "VEC2", 3, true);
  const int c = g.addAccessor(g.addView(gltfStrided(col, 3, 4), 4), 5121, "VEC3", 3, true);
  const int i = g.addAccessor(g.addView(gltfBytes(idx)), 5121, "SCALAR", 3);
  g.addMeshNode({{"POSITION", p}, {"NORMAL", n}, {"TEXCOORD_0", t}, {"COLOR_0", c}}, i);
  g.doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  g.doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  const SceneFile f = loadGltf(g.write(test::scratchDir() + "/q.gltf"), gltfAccessorOptions());
  ASSERT_EQ(f.meshes.size(), 1u);
  const Mesh& m = f.meshes[0];
  ASSERT_EQ(m.vertexCount, 3u);
  for (size_t k = 0; k < 9; ++k) {
    EXPECT_EQ(m.positions[k], float(pos[k])) << k;
    EXPECT_FLOAT_EQ(m.vertexNormals[k], std::max(float(nrm[k]) / 127.0f, -1.0f)) << k;
  }
  for (size_t k = 0; k < 6; ++k) EXPECT_FLOAT_EQ(m.texcoords[k], float(uv[k]) / 65535.0f) << k;
  for (size_t v = 0; v < 3; ++v) {
    for (size_t k = 0; k < 3; ++k)
      EXPECT_FLOAT_EQ(m.vertexColors[4 * v + k], float(col[3 * v + k]) / 255.0f);
    EXPECT_EQ(m.vertexColors[4 * v + 3], 1.0f);
  }
  EXPECT_EQ(m.vertexNormals[2], -1.0f);  // -128 / 127 clamps to -1
  EXPECT_EQ(test::asVector(m.indices), (std::vector<uint32_t>{0, 1, 2}));
  // No material: the one default material is appended and used.
  EXPECT_EQ(f.materialNames, std::vector<std::string>{"default"});
  EXPECT_EQ(m.faceMaterials, std::vector<uint32_t>{0});
  EXPECT_EQ(f.instanceNames, std::vector<std::string>{"node_0"});
  EXPECT_EQ(f.meshNames, std::vector<std::string>{"mesh_0"});
}

TEST(GltfAccessors, IndexTypesAndByteOffset) {
  for (int type : {5121, 5123, 5125}) {
    SCOPED_TRACE(type);
    RawGltf g;
    const std::vector<float> pos = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const int p = g.addAccessor(g.addView(gltfBytes(pos)), 5126, "VEC3", 4);
    const std::vector<uint32_t> want = {3, 2, 1, 0, 1, 3};
    std::vector<unsigned char> bytes(4, 0xEE);  // 4 bytes skipped by byteOffset
    for (uint32_t v : want) {
      const size_t size = type == 5121 ? 1 : type == 5123 ? 2 : 4;
      for (size_t b = 0; b < size; ++b) bytes.push_back(static_cast<unsigned char>(v >> (8 * b)));
    }
    const int i = g.addAccessor(g.addView(bytes), type, "SCALAR", want.size(), false, 4);
    g.addMeshNode({{"POSITION", p}}, i);
    const SceneFile f = loadGltf(g.write(test::scratchDir() + "/i.gltf"));
    EXPECT_EQ(test::asVector(f.meshes[0].indices), want);
  }
}

TEST(GltfAccessors, SparseOverBaseViewAndOverZeros) {
  RawGltf g;
  const std::vector<float> base = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<uint16_t> where = {1, 3};
  const std::vector<float> values = {5, 6, 7, -1, -2, -3};
  const int p = g.addAccessor(g.addView(gltfBytes(base)), 5126, "VEC3", 4);
  const int sparseIndices = g.addView(gltfBytes(where));
  const int sparseValues = g.addView(gltfBytes(values));
  g.doc["accessors"][size_t(p)]["sparse"] = {
      {"count", 2},
      {"indices", {{"bufferView", sparseIndices}, {"componentType", 5123}}},
      {"values", {{"bufferView", sparseValues}}}};
  // Normals: no bufferView, so zeros with the same sparse values.
  const int n = g.addAccessor(-1, 5126, "VEC3", 4);
  g.doc["accessors"][size_t(n)]["sparse"] = g.doc["accessors"][size_t(p)]["sparse"];
  g.addMeshNode({{"POSITION", p}, {"NORMAL", n}}, -1, 6);
  const SceneFile f = loadGltf(g.write(test::scratchDir() + "/s.gltf"), gltfAccessorOptions());
  const Mesh& m = f.meshes[0];
  EXPECT_EQ(test::asVector(m.positions),
            (std::vector<float>{0, 0, 0, 5, 6, 7, 1, 1, 0, -1, -2, -3}));
  EXPECT_EQ(m.vertexNormals, (std::vector<float>{0, 0, 0, 5, 6, 7, 0, 0, 0, -1, -2, -3}));
}

TEST(GltfAccessors, StripsAndFansFollowTheSpec) {
  test::GltfScene s;
  test::GltfPrimitive strip;
  strip.positions.resize(3 * 6, 0.0f);
  for (size_t v = 0; v < 6; ++v) strip.positions[3 * v] = float(v);
  strip.mode = 5;
  test::GltfPrimitive fan = strip;
  fan.mode = 6;
  fan.indices = {5, 4, 3, 2, 1};
  test::GltfPrimitive points = strip;
  points.mode = 0;
  test::GltfPrimitive lines = strip;
  lines.mode = 1;
  s.meshes = {{"m", {strip, points, fan, lines}}};
  s.nodes.resize(1);
  s.nodes[0].mesh = 0;
  s.roots = {0};
  const SceneFile f = loadGltf(test::writeGltf(s, test::scratchDir() + "/sf.glb"));
  const Mesh& m = f.meshes[0];
  EXPECT_EQ(m.vertexCount, 12u);  // strip 6 + fan 6; points and lines skipped
  EXPECT_EQ(f.skippedPrimitives, 2u);
  // Strip (glTF 2.0, 3.7.2.1): (0 1 2) (1 3 2) (2 3 4) (3 5 4). Fan: vertices 6.. (indices
  // 5 4 3 2 1 + 6): (10 9 11) (9 8 11) (8 7 11).
  EXPECT_EQ(test::asVector(m.indices), (std::vector<uint32_t>{0, 1,  2, 1,  3, 2, 2,  3, 4, 3, 5,
                                                              4, 10, 9, 11, 9, 8, 11, 8, 7, 11}));
}

TEST(GltfAccessors, PrimitivesConcatenateWithDefaultsForMissingAttributes) {
  test::GltfScene s;
  test::GltfPrimitive a;
  a.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  a.colors = {0.5f, 0.5f, 0.5f, 1, 0.5f, 0.5f, 0.5f, 1, 0.5f, 0.5f, 0.5f, 1};
  a.uv = {0, 0, 1, 0, 0, 1};
  a.material = 0;
  test::GltfPrimitive b;
  b.positions = {0, 0, 1, 1, 0, 1, 0, 1, 1};
  b.indices = {2, 1, 0};
  s.meshes = {{"", {a, b}}};
  s.materials.resize(1);
  s.nodes.resize(1);
  s.nodes[0].mesh = 0;
  s.roots = {0};
  const SceneFile f =
      loadGltf(test::writeGltf(s, test::scratchDir() + "/c.gltf"), gltfAccessorOptions());
  const Mesh& m = f.meshes[0];
  EXPECT_EQ(test::asVector(m.indices), (std::vector<uint32_t>{0, 1, 2, 5, 4, 3}));
  EXPECT_EQ(m.texcoords, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0}));
  std::vector<float> colors = a.colors;
  colors.resize(24, 1.0f);
  EXPECT_EQ(m.vertexColors, colors);
  EXPECT_EQ(m.faceMaterials, (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(f.materialNames, (std::vector<std::string>{"material_0", "default"}));
  EXPECT_EQ(f.materials[1].baseColor, glm::vec4(1.0f));
}

}  // namespace
}  // namespace aperture
