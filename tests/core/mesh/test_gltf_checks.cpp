// Bad glTF input: every case is an Error naming the file and the JSON pointer of the bad
// element; required extensions refused or, for texture-only ones, marking their materials.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/mesh/scene_file.h"
#include "core/util/error.h"
#include "tests/gltf_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using nlohmann::json;

/// One indexed triangle with a material, placed by node 0 (accessor 0 POSITION, 1 indices;
/// views 0 and 1), plus a camera node 1.
test::GltfScene gltfCheckedTriangle() {
  test::GltfScene s;
  test::GltfPrimitive p;
  p.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  p.indices = {0, 1, 2};
  p.material = 0;
  s.meshes = {{"tri", {p}}};
  s.materials.resize(1);
  s.cameras.resize(1);
  s.nodes.resize(2);
  s.nodes[0].mesh = 0;
  s.nodes[1].camera = 0;
  s.roots = {0, 1};
  return s;
}

/// Loading `path` throws an Error whose message holds the path and every one of `parts`.
void expectGltfError(const std::string& path, const std::vector<std::string>& parts,
                     const LoadOptions& options = {}) {
  try {
    loadGltf(path, options);
    ADD_FAILURE() << "no error for " << path;
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
    for (const std::string& part : parts)
      EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
  }
}

/// The triangle written to a fresh .gltf, edited by `edit`.
std::string gltfEditedTriangle(const std::function<void(json&)>& edit) {
  static int serial = 0;
  const std::string path = test::writeGltf(
      gltfCheckedTriangle(), test::scratchDir() + "/t" + std::to_string(serial++) + ".gltf");
  test::editGltf(path, edit);
  return path;
}

TEST(GltfChecks, TheUneditedFileLoads) {
  const std::string path = test::writeGltf(gltfCheckedTriangle(), test::scratchDir() + "/t.gltf");
  EXPECT_EQ(loadGltf(path).meshes.size(), 1u);
}

TEST(GltfChecks, BadJson) {
  const std::string path = test::scratchDir() + "/bad.gltf";
  std::ofstream(path) << "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [";
  expectGltfError(path, {"invalid JSON"});
}

TEST(GltfChecks, AccessorPastItsView) {
  expectGltfError(gltfEditedTriangle([](json& d) { d["accessors"][0]["count"] = 4; }),
                  {"/accessors/0/count", "buffer view 0"});
  expectGltfError(gltfEditedTriangle([](json& d) { d["accessors"][0]["byteOffset"] = 400; }),
                  {"/accessors/0/byteOffset"});
}

TEST(GltfChecks, ViewPastItsBufferAndShortBuffer) {
  expectGltfError(gltfEditedTriangle([](json& d) { d["bufferViews"][1]["byteLength"] = 4000; }),
                  {"/bufferViews/1/byteLength", "buffer 0"});
  expectGltfError(gltfEditedTriangle([](json& d) { d["bufferViews"][1]["byteOffset"] = 4000; }),
                  {"/bufferViews/1/byteOffset"});
  expectGltfError(gltfEditedTriangle([](json& d) { d["buffers"][0]["byteLength"] = 4000; }),
                  {"/buffers/0/byteLength", "4000"});
}

TEST(GltfChecks, IndexOutOfRangeOfTheVertices) {
  test::RawGltf g;
  const std::vector<float> pos = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<uint16_t> idx = {0, 1, 5};
  const int p = g.addAccessor(g.addView(test::gltfBytes(pos)), 5126, "VEC3", 3);
  const int i = g.addAccessor(g.addView(test::gltfBytes(idx)), 5123, "SCALAR", 3);
  g.addMeshNode({{"POSITION", p}}, i);
  expectGltfError(g.write(test::scratchDir() + "/i.gltf"),
                  {"/accessors/1", "index 5", "3 vertices"});
}

TEST(GltfChecks, NodeGraphCycleAndTwoParents) {
  expectGltfError(gltfEditedTriangle([](json& d) {
                    d["nodes"][0]["children"] = {1};
                    d["nodes"][1]["children"] = {0};
                  }),
                  {"/nodes/", "/children", "cycle"});
  expectGltfError(gltfEditedTriangle([](json& d) {
                    d["nodes"].push_back({{"children", {0}}});
                    d["nodes"].push_back({{"children", {0}}});
                  }),
                  {"/nodes/3/children", "node 0 is also a child of node 2"});
  expectGltfError(gltfEditedTriangle([](json& d) { d["nodes"][0]["children"] = {0}; }),
                  {"/nodes/0/children", "own child"});
}

TEST(GltfChecks, MissingFilesAndBadDataUris) {
  const std::string dir = test::scratchDir();
  const std::string path = test::writeGltf(gltfCheckedTriangle(), dir + "/missing_bin.gltf");
  std::filesystem::remove(dir + "/missing_bin.bin");
  expectGltfError(path, {"/buffers/0/uri", "missing_bin.bin"});
  expectGltfError(gltfEditedTriangle([](json& d) {
                    d["buffers"][0]["uri"] = "data:application/octet-stream,not base64!";
                  }),
                  {"/buffers/0/uri", "not base64"});
  expectGltfError(gltfEditedTriangle([](json& d) {
                    d["images"] = {{{"uri", "missing.png"}}};
                  }),
                  {"/images/0/uri", "missing.png"});
  expectGltfError(gltfEditedTriangle([](json& d) {
                    d["images"] = {{{"uri", "data:image/png;base64,@@@"}}};
                  }),
                  {"/images/0/uri", "not base64"});
}

TEST(GltfChecks, IndicesOutOfRange) {
  expectGltfError(gltfEditedTriangle([](json& d) { d["nodes"][0]["mesh"] = 3; }),
                  {"/nodes/0/mesh", "mesh 3 does not exist"});
  expectGltfError(gltfEditedTriangle([](json& d) { d["nodes"][1]["camera"] = 1; }),
                  {"/nodes/1/camera"});
  expectGltfError(
      gltfEditedTriangle([](json& d) { d["meshes"][0]["primitives"][0]["material"] = 7; }),
      {"/meshes/0/primitives/0/material"});
  expectGltfError(gltfEditedTriangle([](json& d) {
                    d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 9;
                  }),
                  {"/meshes/0/primitives/0/attributes/POSITION", "accessor 9"});
  expectGltfError(gltfEditedTriangle([](json& d) { d["accessors"][1]["bufferView"] = 5; }),
                  {"/accessors/1/bufferView"});
  expectGltfError(gltfEditedTriangle([](json& d) { d["scene"] = 2; }), {"/scene"});
  LoadOptions options;
  options.gltfScene = 4;
  expectGltfError(gltfEditedTriangle([](json&) {}), {"/scenes", "1 scenes"}, options);
}

TEST(GltfChecks, RequiredExtensions) {
  expectGltfError(gltfEditedTriangle([](json& d) {
                    d["extensionsRequired"] = {"KHR_mesh_quantization", "EXT_mesh_gpu_instancing"};
                  }),
                  {"/extensionsRequired/1", "EXT_mesh_gpu_instancing"});
  // A texture-only extension marks the materials that use it; the geometry loads.
  const std::string path = gltfEditedTriangle([](json& d) {
    d["extensionsUsed"] = {"KHR_texture_basisu"};
    d["extensionsRequired"] = {"KHR_texture_basisu"};
    d["images"] = {{{"uri", d["buffers"][0]["uri"]}}};  // any file: its bytes are not read
    d["textures"] = {{{"extensions", {{"KHR_texture_basisu", {{"source", 0}}}}}}};
    d["materials"].push_back(json::object());
    d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
  });
  const SceneFile f = loadGltf(path);
  ASSERT_EQ(f.materials.size(), 2u);
  EXPECT_EQ(f.materials[0].unsupported, "KHR_texture_basisu");
  EXPECT_EQ(f.materials[0].baseColorTexture, -1);
  EXPECT_EQ(f.materials[1].unsupported, "");
  EXPECT_EQ(f.meshes[0].triangleCount(), 1u);
}

TEST(GltfChecks, SecondTexCoordIsUnsupportedForAlbedo) {
  test::GltfScene s = gltfCheckedTriangle();
  s.materials[0].png = test::checkerPng(4, 2);
  s.materials[0].texCoord = 1;
  const SceneFile f = loadGltf(test::writeGltf(s, test::scratchDir() + "/tc.glb"));
  EXPECT_NE(f.materials[0].unsupported.find("texCoord 1"), std::string::npos)
      << f.materials[0].unsupported;
  EXPECT_EQ(f.materials[0].baseColorTexture, -1);
}

TEST(GltfChecks, ChosenSceneAndOrthographicCamera) {
  test::GltfScene s = gltfCheckedTriangle();
  s.cameras[0].orthographic = true;
  s.cameras[0].xmag = 2;
  s.cameras[0].ymag = 3;
  s.cameras[0].znear = 0.5;
  s.cameras[0].zfar = 50;
  const std::string path = test::writeGltf(s, test::scratchDir() + "/o.gltf");
  test::editGltf(path, [](json& d) {
    d["scenes"].push_back({{"nodes", {1}}});
    d["scene"] = 1;
  });
  SceneFile f = loadGltf(path);
  EXPECT_TRUE(f.instances.empty());  // scene 1 holds only the camera node
  ASSERT_EQ(f.cameras.size(), 1u);
  EXPECT_EQ(f.cameras[0].name, "camera_1");
  EXPECT_EQ(f.cameras[0].projection, SceneCamera::Projection::Orthographic);
  EXPECT_EQ(f.cameras[0].xmag, 2);
  EXPECT_EQ(f.cameras[0].ymag, 3);
  EXPECT_EQ(f.cameras[0].znear, 0.5);
  EXPECT_EQ(f.cameras[0].zfar, std::optional<double>(50));
  LoadOptions options;
  options.gltfScene = 0;
  f = loadGltf(path, options);
  EXPECT_EQ(f.instances.size(), 1u);
}

}  // namespace
}  // namespace aperture
