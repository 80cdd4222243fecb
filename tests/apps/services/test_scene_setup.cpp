// The scene set-up over scene files (apps/services/scene_setup.h): what each AOV makes the
// loaders keep, ids numbered scene-wide over placements, a mesh placed several times built
// once, a file placed once finished exactly as loadMesh finishes it, and --gltf-scene refused
// where no glTF file is given.
#include <gtest/gtest.h>

#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <string>
#include <vector>

#include "apps/services/scene_setup.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// A quad of two triangles in z = `z`, x and y in [-1, 1] shifted by `x0` in x (ASCII PLY).
std::string quadPly(double x0, double z) {
  return cat("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n",
             "property float z\nelement face 2\nproperty list uchar int vertex_indices\n",
             "end_header\n", x0 - 1, " -1 ", z, "\n", x0 + 1, " -1 ", z, "\n", x0 + 1, " 1 ", z,
             "\n", x0 - 1, " 1 ", z, "\n3 0 1 2\n3 0 2 3\n");
}

TEST(SceneSetupNeeds, EachAovLoadsOnlyWhatItReads) {
  struct Case {
    AovMask aovs;
    bool texcoords, vertexColors, materials, groups, textures;
  };
  const Case cases[] = {
      {kAovDepth | kAovNormal | kAovPrimId | kAovGeomId, false, false, false, false, false},
      {kAovMeshId | kAovBarycentric, false, false, false, false, false},
      {kAovUv, true, false, false, false, false},
      {kAovVertexColor, false, true, false, false, false},
      {kAovMaterialId, false, false, true, false, false},
      {kAovInstanceId, false, false, false, true, false},
      {kAovAlbedo, true, true, true, false, true},
  };
  for (const Case& c : cases) {
    const app::SceneSpec s = app::withAovNeeds({}, AovSet(c.aovs));
    EXPECT_EQ(s.texcoords, c.texcoords) << c.aovs;
    EXPECT_EQ(s.vertexColors, c.vertexColors) << c.aovs;
    EXPECT_EQ(s.materials, c.materials) << c.aovs;
    EXPECT_EQ(s.groups, c.groups) << c.aovs;
    EXPECT_EQ(s.textures, c.textures) << c.aovs;
  }
  // Asking for less again drops what an earlier set asked for.
  app::SceneSpec s = app::withAovNeeds({}, AovSet(kAovAlbedo | kAovInstanceId));
  s = app::withAovNeeds(s, AovSet(kAovDepth));
  EXPECT_FALSE(s.texcoords || s.vertexColors || s.materials || s.groups || s.textures);
}

TEST(SceneSetupIds, PlacementsAreNumberedSceneWideAndARepeatedFileIsBuiltOnce) {
  const std::string dir = test::scratchDir();
  const std::string a = dir + "/a.ply", b = dir + "/b.ply";
  test::writeFile(a, quadPly(0, 0));
  test::writeFile(b, quadPly(5, 1));
  app::SceneSpec spec;
  const glm::dmat4 shift = glm::translate(glm::dmat4(1.0), glm::dvec3(0, 0, -3));
  spec.meshes = {{a, std::nullopt}, {b, shift}, {a, shift}};
  Device device;
  const app::LoadedScene s = app::loadScene(device, spec, true);
  ASSERT_EQ(s.objects.size(), 3u);
  // A PLY placement holds one instance and one mesh, named after the file's stem.
  EXPECT_EQ(s.ids.instance, (std::vector<std::string>{"a", "b", "a"}));
  EXPECT_EQ(s.ids.mesh, (std::vector<std::string>{"a", "b", "a"}));
  EXPECT_TRUE(s.ids.material.empty());
  for (uint32_t k = 0; k < 3; ++k) {
    EXPECT_EQ(s.scene->objectIds(k).instance, k);
    EXPECT_EQ(s.scene->objectIds(k).mesh, k);
    EXPECT_EQ(s.scene->objectIds(k).materialBase, 0u);
  }
  // a.ply is finished once and instanced twice; b.ply is attached directly.
  EXPECT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(s.objects[0].mesh, s.objects[2].mesh);
  EXPECT_EQ(s.scene->stats().triangles, 6u);
  EXPECT_EQ(s.scene->stats().uniqueTriangles, 4u);
  EXPECT_EQ(s.objects[2].worldFromMesh, shift);
  EXPECT_EQ(s.objects[1].worldFromMesh, glm::dmat4(1.0));
}

TEST(SceneSetupIds, AFilePlacedOnceIsFinishedAsLoadMeshFinishesIt) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper_res4.ply");
  app::SceneSpec spec;
  glm::dmat4 place = glm::rotate(glm::dmat4(1.0), 0.7, glm::dvec3(0.3, 1, 0.2));
  place = glm::translate(place, glm::dvec3(1e5, -3, 2.5));
  spec.meshes = {{path, place}};
  const app::LoadedScene s = app::loadSceneMeshes(spec, true);
  LoadOptions lo;
  lo.transform = place;
  const Mesh want = loadMesh(path, lo);
  ASSERT_EQ(s.meshes.size(), 1u);
  const Mesh& got = s.meshes.front();
  EXPECT_EQ(got.anchor, want.anchor);
  ASSERT_EQ(got.positions.size(), want.positions.size());
  EXPECT_EQ(std::memcmp(got.positions.data(), want.positions.data(),
                        want.positions.size() * sizeof(float)),
            0);
  ASSERT_EQ(got.indices.size(), want.indices.size());
  EXPECT_EQ(
      std::memcmp(got.indices.data(), want.indices.data(), want.indices.size() * sizeof(uint32_t)),
      0);
  EXPECT_EQ(s.objects.front().worldFromMesh, glm::dmat4(1.0));
  EXPECT_EQ(s.renderOrigin, want.anchor);
}

TEST(SceneSetupIds, GltfSceneNeedsAGltfFile) {
  app::SceneSpec spec;
  spec.meshes = {{"procedural:sphere", std::nullopt}};
  spec.gltfScene = 1;
  std::string msg = test::errorOf([&] { app::loadSceneMeshes(spec, true); });
  EXPECT_NE(msg.find("--gltf-scene 1: no glTF file"), std::string::npos) << msg;
  spec.gltfScene = -1;
  msg = test::errorOf([&] { app::loadSceneMeshes(spec, true); });
  EXPECT_NE(msg.find("--gltf-scene -1: must be >= 0"), std::string::npos) << msg;
}

}  // namespace
}  // namespace aperture
