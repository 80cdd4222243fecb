// EXT_meshopt_compression filters (OCTAHEDRAL, QUATERNION, EXPONENTIAL) against the values
// before encoding, within the precision of each encoding; an empty fallback buffer. The plain
// Draco and meshopt layouts are compared bit for bit with .gltf + .bin in test_gltf.cpp.
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <cmath>

#include "core/mesh/scene_file.h"
#include "core/util/error.h"
#include "tests/gltf_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using nlohmann::json;
using test::RawGltf;

/// Appends a meshopt ATTRIBUTES view of `count` elements of `stride` bytes (`raw`, already
/// filter-encoded) to `g`: the compressed bytes in buffer 0, the view in fallback buffer 1.
int gltfMeshoptView(RawGltf& g, const std::vector<unsigned char>& raw, size_t count, int stride,
                    const char* filter) {
  std::vector<unsigned char> encoded(meshopt_encodeVertexBufferBound(count, size_t(stride)));
  encoded.resize(meshopt_encodeVertexBuffer(encoded.data(), encoded.size(), raw.data(), count,
                                            size_t(stride)));
  const int compressed = g.addView(encoded);
  const size_t at = g.doc["bufferViews"][size_t(compressed)]["byteOffset"];
  if (!g.doc.contains("buffers"))
    g.doc["buffers"] = {{{"byteLength", 4096},
                         {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}}};
  g.doc["bufferViews"].push_back({{"buffer", 1},
                                  {"byteLength", raw.size()},
                                  {"byteStride", stride},
                                  {"extensions",
                                   {{"EXT_meshopt_compression",
                                     {{"buffer", 0},
                                      {"byteOffset", at},
                                      {"byteLength", encoded.size()},
                                      {"byteStride", stride},
                                      {"count", count},
                                      {"mode", "ATTRIBUTES"},
                                      {"filter", filter}}}}}});
  return int(g.doc["bufferViews"].size() - 1);
}

TEST(GltfCompression, MeshoptFilters) {
  const size_t n = 3;
  // Unit normals, octahedral-encoded in 16-bit signed components (stride 8).
  const std::vector<float> normals = {0, 0, 1, 0, 0.6f, 0.8f, 0, 0, -0.48f, 0.6f, 0.64f, 0};
  std::vector<unsigned char> oct(n * 8);
  meshopt_encodeFilterOct(oct.data(), n, 8, 16, normals.data());
  // Positions with a shared 24-bit mantissa per vector.
  const std::vector<float> positions = {1.5f,  -2.25f,  1000.0f, 0.125f, 3.0f,
                                        -7.5f, -0.001f, 0.5f,    2.0f};
  std::vector<unsigned char> exp(n * 12);
  meshopt_encodeFilterExp(exp.data(), n, 12, 24, positions.data());
  // Unit quaternions (16-bit), read back as COLOR_0 through a normalized short accessor.
  const float h = std::sqrt(0.5f);
  const std::vector<float> quats = {0, 0, 0, 1, h, 0, 0, h, 0.5f, 0.5f, 0.5f, 0.5f};
  std::vector<unsigned char> quat(n * 8);
  meshopt_encodeFilterQuat(quat.data(), n, 8, 16, quats.data());

  RawGltf g;
  const int p = g.addAccessor(gltfMeshoptView(g, exp, n, 12, "EXPONENTIAL"), 5126, "VEC3", n);
  const int nm = g.addAccessor(gltfMeshoptView(g, oct, n, 8, "OCTAHEDRAL"), 5122, "VEC3", n, true);
  const int c = g.addAccessor(gltfMeshoptView(g, quat, n, 8, "QUATERNION"), 5122, "VEC4", n, true);
  g.addMeshNode({{"POSITION", p}, {"NORMAL", nm}, {"COLOR_0", c}});
  g.doc["extensionsUsed"] = {"EXT_meshopt_compression", "KHR_mesh_quantization"};
  g.doc["extensionsRequired"] = g.doc["extensionsUsed"];
  LoadOptions options;
  options.vertexNormals = options.vertexColors = true;
  const SceneFile f = loadGltf(g.write(test::scratchDir() + "/filters.gltf"), options);
  const Mesh& m = f.meshes[0];
  ASSERT_EQ(m.vertexCount, n);
  for (size_t k = 0; k < 3 * n; ++k) {
    // A 24-bit mantissa shared by the vector: relative to its largest component.
    const size_t v = k / 3;
    const float scale = std::max({std::fabs(positions[3 * v]), std::fabs(positions[3 * v + 1]),
                                  std::fabs(positions[3 * v + 2])});
    EXPECT_NEAR(m.positions[k], positions[k], scale * 1e-6f) << k;
    EXPECT_NEAR(m.vertexNormals[k], normals[4 * v + k % 3], 1e-3f) << k;
  }
  for (size_t k = 0; k < 4 * n; ++k) {
    // q and -q are the same rotation: compare up to the sign of the quaternion.
    const size_t v = k / 4;
    const float sign = m.vertexColors[4 * v + 3] * quats[4 * v + 3] < 0 ? -1.0f : 1.0f;
    EXPECT_NEAR(sign * m.vertexColors[k], quats[k], 1e-3f) << k;
  }
}

TEST(GltfCompression, MeshoptCountBeyondItsBytesIsRefused) {
  const std::string path = test::writeGltf(test::issue41Scene(), test::scratchDir() + "/m.gltf",
                                           test::GltfCompression::Meshopt);
  test::editGltf(path, [](json& d) {
    d["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["count"] = 100000000;
  });
  try {
    loadGltf(path);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/bufferViews/0/extensions/EXT_meshopt_compression/count"),
              std::string::npos)
        << e.what();
  }
}

TEST(GltfCompression, DracoDataThatDoesNotDecode) {
  const std::string path = test::writeGltf(test::issue41Scene(), test::scratchDir() + "/d.gltf",
                                           test::GltfCompression::Draco);
  // Point the first Draco primitive at the image's buffer view (PNG bytes, not Draco).
  test::editGltf(path, [](json& d) {
    d["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["bufferView"] =
        d["images"][0]["bufferView"];
  });
  try {
    loadGltf(path);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression/bufferView"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace aperture

namespace aperture {
namespace {

// Found by fuzz_gltf (tests/fuzz/regressions/gltf): an uncompressed view in the empty fallback
// buffer was read past its one byte.
TEST(GltfCompression, PlainViewInAnEmptyFallbackIsRefused) {
  const std::string path = test::writeGltf(test::issue41Scene(), test::scratchDir() + "/f.gltf",
                                           test::GltfCompression::Meshopt);
  size_t view = 0;
  test::editGltf(path, [&](nlohmann::json& d) {
    d["bufferViews"].push_back({{"buffer", 1}, {"byteLength", 8}});
    view = d["bufferViews"].size() - 1;
  });
  try {
    loadGltf(path);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/bufferViews/" + std::to_string(view) + "/buffer"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace aperture
