// The glTF 2.0 loader on files written by tests/gltf_support (an independent writer): the
// issue 41 scene in its four layouts, transforms, instancing, materials, textures, cameras.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "core/mesh/scene_file.h"
#include "core/util/error.h"
#include "tests/gltf_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::GltfCompression;
using test::GltfScene;

LoadOptions gltfEverything() {
  LoadOptions o;
  o.vertexNormals = o.texcoords = o.vertexColors = o.materials = true;
  return o;
}

void expectGltfMatrix(const glm::dmat4& a, const glm::dmat4& b) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      EXPECT_NEAR(a[c][r], b[c][r], 1e-12) << "[" << c << "][" << r << "]";
}

TEST(Gltf, Issue41SceneTransformsAndInstancing) {
  const GltfScene s = test::issue41Scene();
  const std::string path = test::writeGltf(s, test::scratchDir() + "/scene.gltf");
  const SceneFile f = loadGltf(path, gltfEverything());
  ASSERT_EQ(f.meshes.size(), 2u);
  ASSERT_EQ(f.instances.size(), 4u);
  // Depth first in node order: quad_a (1), quad_b (2), quad_c (4), tri (5).
  const glm::dmat4 root = test::gltfLocalMatrix(s.nodes[0]);
  const glm::dmat4 group = root * test::gltfLocalMatrix(s.nodes[3]);
  const std::vector<std::pair<uint32_t, glm::dmat4>> expected = {
      {1, root * test::gltfLocalMatrix(s.nodes[1])},
      {2, root * test::gltfLocalMatrix(s.nodes[2])},
      {4, group * test::gltfLocalMatrix(s.nodes[4])},
      {5, group * test::gltfLocalMatrix(s.nodes[5])}};
  for (size_t i = 0; i < expected.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(f.instances[i].id, expected[i].first);
    EXPECT_EQ(f.instances[i].mesh, i < 3 ? 0u : 1u);
    expectGltfMatrix(f.instances[i].worldFromMesh, expected[i].second);
  }
  EXPECT_EQ(f.instanceNames, (std::vector<std::string>{"root", "quad_a", "quad_b", "group",
                                                       "quad_c", "tri", "camera"}));
  EXPECT_EQ(f.meshNames, (std::vector<std::string>{"quad", "tri"}));
  EXPECT_EQ(f.materialNames, (std::vector<std::string>{"checker", "red"}));
  ASSERT_EQ(f.cameras.size(), 1u);
  EXPECT_EQ(f.cameras[0].name, "camera");
  EXPECT_EQ(f.cameras[0].node, 6u);
  EXPECT_EQ(f.cameras[0].projection, SceneCamera::Projection::Perspective);
  EXPECT_DOUBLE_EQ(f.cameras[0].yfov, 0.8);
  EXPECT_EQ(f.cameras[0].aspectRatio, std::optional<double>(1.5));
  EXPECT_DOUBLE_EQ(f.cameras[0].znear, 0.1);
  EXPECT_EQ(f.cameras[0].zfar, std::optional<double>(100));
  expectGltfMatrix(f.cameras[0].worldFromCamera, test::gltfLocalMatrix(s.nodes[6]));
  EXPECT_EQ(f.skippedPrimitives, 0u);
}

TEST(Gltf, Issue41SceneMeshesMaterialsAndTexture) {
  const GltfScene s = test::issue41Scene();
  const std::string path = test::writeGltf(s, test::scratchDir() + "/scene.glb");
  const SceneFile f = loadGltf(path, gltfEverything());
  ASSERT_EQ(f.meshes.size(), 2u);
  const Mesh& quad = f.meshes[0];
  const test::GltfPrimitive& q = s.meshes[0].primitives[0];
  EXPECT_EQ(quad.vertexCount, 4u);
  EXPECT_EQ(test::asVector(quad.positions), q.positions);
  EXPECT_EQ(test::asVector(quad.indices), q.indices);
  EXPECT_EQ(quad.vertexNormals, q.normals);
  EXPECT_EQ(quad.texcoords, q.uv);
  EXPECT_EQ(quad.vertexColors, q.colors);
  EXPECT_EQ(quad.faceMaterials, (std::vector<uint32_t>{0, 0}));
  EXPECT_EQ(f.meshes[1].faceMaterials, (std::vector<uint32_t>{1}));
  EXPECT_EQ(test::asVector(f.meshes[1].indices), (std::vector<uint32_t>{0, 1, 2}));
  ASSERT_EQ(f.materials.size(), 2u);
  EXPECT_EQ(f.materials[1].baseColor, glm::vec4(1, 0, 0, 1));
  EXPECT_EQ(f.materials[1].baseColorTexture, -1);
  ASSERT_EQ(f.materials[0].baseColorTexture, 0);
  ASSERT_EQ(f.textures.size(), 1u);
  EXPECT_EQ(f.textures[0].where, path + ": /images/0");
  EXPECT_EQ(f.textures[0].bytes, test::checkerPng(8, 2));
  EXPECT_EQ(f.textures[0].mimeType, "image/png");
  EXPECT_TRUE(f.textures[0].path.empty());
  EXPECT_TRUE(f.textures[0].nearest);
  EXPECT_EQ(f.textures[0].wrapS, TextureWrap::Repeat);
}

TEST(Gltf, LayoutsGiveIdenticalMeshes) {
  const GltfScene s = test::issue41Scene();
  const std::string dir = test::scratchDir();
  const SceneFile reference = loadGltf(test::writeGltf(s, dir + "/a.gltf"), gltfEverything());
  for (const auto& [name, compression] :
       std::vector<std::pair<std::string, GltfCompression>>{{"b.glb", GltfCompression::None},
                                                            {"c.gltf", GltfCompression::Draco},
                                                            {"d.glb", GltfCompression::Draco},
                                                            {"e.gltf", GltfCompression::Meshopt},
                                                            {"f.glb", GltfCompression::Meshopt}}) {
    SCOPED_TRACE(name);
    const SceneFile f =
        loadGltf(test::writeGltf(s, dir + "/" + name, compression), gltfEverything());
    ASSERT_EQ(f.meshes.size(), reference.meshes.size());
    for (size_t m = 0; m < f.meshes.size(); ++m) {
      const Mesh& a = reference.meshes[m];
      const Mesh& b = f.meshes[m];
      EXPECT_EQ(b.vertexCount, a.vertexCount);
      // Bit for bit: float equality of finite values, no tolerance.
      EXPECT_EQ(test::asVector(b.positions), test::asVector(a.positions));
      EXPECT_EQ(test::asVector(b.indices), test::asVector(a.indices));
      EXPECT_EQ(b.vertexNormals, a.vertexNormals);
      EXPECT_EQ(b.texcoords, a.texcoords);
      EXPECT_EQ(b.vertexColors, a.vertexColors);
      EXPECT_EQ(b.faceMaterials, a.faceMaterials);
    }
    ASSERT_EQ(f.instances.size(), reference.instances.size());
    for (size_t i = 0; i < f.instances.size(); ++i)
      EXPECT_EQ(f.instances[i].worldFromMesh, reference.instances[i].worldFromMesh);
    EXPECT_EQ(f.textures.size(), reference.textures.size());
  }
}

TEST(Gltf, ExternalBinAndImageAndFileBytes) {
  GltfScene s = test::issue41Scene();
  s.materials[0].externalImage = true;
  const std::string dir = test::scratchDir();
  const std::string path = test::writeGltf(s, dir + "/ext.gltf");
  const SceneFile f = loadGltf(path);
  ASSERT_EQ(f.textures.size(), 1u);
  EXPECT_EQ(f.textures[0].path, dir + "/ext_image0.png");
  EXPECT_TRUE(f.textures[0].bytes.empty());
  EXPECT_EQ(f.fileBytes,
            std::filesystem::file_size(path) + std::filesystem::file_size(dir + "/ext.bin"));
  // Unasked surface data is not stored.
  EXPECT_TRUE(f.meshes[0].texcoords.empty());
  EXPECT_TRUE(f.meshes[0].vertexColors.empty());
  EXPECT_TRUE(f.meshes[0].faceMaterials.empty());
  EXPECT_TRUE(f.meshes[0].vertexNormals.empty());
}

}  // namespace
}  // namespace aperture

namespace aperture {
namespace {

// The seeds of the glTF fuzz target (tests/fuzz/corpus/gltf) are files of this writer: they
// must load. APERTURE_WRITE_GLTF_SEEDS=1 rewrites them (then commit them).
TEST(Gltf, FuzzSeedsLoad) {
  const std::string dir = std::string(APERTURE_TESTS_DIR) + "/fuzz/corpus/gltf";
  test::GltfScene s = test::issue41Scene();
  s.materials[0].png = test::checkerPng(2, 2);  // small seeds
  if (std::getenv("APERTURE_WRITE_GLTF_SEEDS")) {
    std::filesystem::create_directories(dir);
    test::writeGltf(s, dir + "/scene.glb");
    test::writeGltf(s, dir + "/draco.glb", GltfCompression::Draco);
    test::writeGltf(s, dir + "/meshopt.glb", GltfCompression::Meshopt);
  }
  for (const char* name : {"scene.glb", "draco.glb", "meshopt.glb"}) {
    SCOPED_TRACE(name);
    const SceneFile f = loadGltf(dir + "/" + name, gltfEverything());
    EXPECT_EQ(f.meshes.size(), 2u);
    EXPECT_EQ(f.instances.size(), 4u);
  }
}

}  // namespace
}  // namespace aperture

namespace aperture {
namespace {

TEST(Gltf, DataUriImageAndEscapedExternalUri) {
  test::GltfScene s = test::issue41Scene();
  const std::vector<unsigned char> png = test::checkerPng(4, 2);
  const std::string uri = test::dataUri(png);
  s.materials[0].png.clear();
  s.materials[0].imageUri = "data:image/png;base64," + uri.substr(uri.find(',') + 1);
  s.materials[0].wrapS = 33071;
  s.materials[0].wrapT = 33648;
  s.materials[0].magFilter = 9729;
  s.materials[1].imageUri = "my%20checker.png";
  const std::string dir = test::scratchDir();
  std::ofstream(dir + "/my checker.png", std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
  const std::string path = test::writeGltf(s, dir + "/uris.gltf");
  const SceneFile f = loadGltf(path);
  ASSERT_EQ(f.textures.size(), 2u);
  EXPECT_EQ(f.textures[0].bytes, png);
  EXPECT_EQ(f.textures[0].mimeType, "image/png");
  EXPECT_EQ(f.textures[0].wrapS, TextureWrap::ClampToEdge);
  EXPECT_EQ(f.textures[0].wrapT, TextureWrap::MirroredRepeat);
  EXPECT_FALSE(f.textures[0].nearest);
  EXPECT_EQ(f.textures[1].path, dir + "/my checker.png");
  EXPECT_EQ(f.textures[1].where, path + ": /images/1");
  EXPECT_EQ(f.materials[1].baseColorTexture, 1);
}

}  // namespace
}  // namespace aperture
