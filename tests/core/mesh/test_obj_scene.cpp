// The OBJ scene loader (loadObjScene, core/mesh/obj.cpp and mtl.cpp): objects from o/g,
// materials from usemtl and the .mtl files, texture coordinates with vertices split per
// (v, vt) pair, and the errors for missing libraries and textures and refused map_Kd options.
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh/scene_file.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// A fresh directory NAME in the test's scratch directory.
std::string sceneDir(const std::string& name) {
  const std::string dir = test::scratchDir() + "/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

LoadOptions everything() {
  LoadOptions o;
  o.texcoords = o.groups = o.materials = true;
  return o;
}

// The scene: 5 positions, 5 texture coordinates; faces before any o/g and usemtl, an `o`,
// a `g` with a name of two words, a quad, an object met again.
const char* const kRoomObj =
    "# a room\n"
    "mtllib room.mtl\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.25 0.75\n"
    "f 1/1 2/2 3/3\n"
    "o chair\n"
    "usemtl red\n"
    "f 1/1 3/3 4/4\n"
    "g table top\n"
    "f 1/5 2/2 5/4 4/1\n"
    "usemtl blue\n"
    "o chair   # again\n"
    "f 2/2 5/4 3/3\n"
    "usemtl red\n"
    "f 3/5 4/4 5/4\n";

// Line 4 holds red's map_Kd; `unused` names a texture that does not exist (not an error:
// no face uses it).
const char* const kRoomMtl =
    "newmtl red\n"
    "Kd 0.8 0.1 0.2\n"
    "# its texture\n"
    "map_Kd -bm 1 textures/red.png\n"
    "newmtl blue\n"
    "Kd 0.1 0.2 0.9\n"
    "newmtl unused\n"
    "map_Kd nowhere.png\n";

/// The room written to `dir`, with its library and texture; returns the .obj path.
std::string writeRoom(const std::string& dir) {
  test::writeFile(dir + "/room.obj", kRoomObj);
  test::writeFile(dir + "/room.mtl", kRoomMtl);
  std::filesystem::create_directories(dir + "/textures");
  test::writeFile(dir + "/textures/red.png", "not really a png");
  return dir + "/room.obj";
}

TEST(ObjScene, ObjectsMaterialsAndTexcoordsOfTheRoom) {
  const std::string dir = sceneDir("obj_scene_room");
  const SceneFile scene = loadObjScene(writeRoom(dir), everything());

  // Read off the file by hand: triangle t's object and material, and its corners as
  // (position number, texture number), 1-based as written, the quad fanned from its first.
  const std::vector<uint32_t> groups = {0, 1, 2, 2, 1, 1};
  const std::vector<uint32_t> materials = {2, 0, 0, 0, 1, 0};
  const std::vector<std::pair<int, int>> corners = {{1, 1}, {2, 2}, {3, 3}, {1, 1}, {3, 3}, {4, 4},
                                                    {1, 5}, {2, 2}, {5, 4}, {1, 5}, {5, 4}, {4, 1},
                                                    {2, 2}, {5, 4}, {3, 3}, {3, 5}, {4, 4}, {5, 4}};
  const double v[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}};
  const double vt[5][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.25, 0.75}};

  ASSERT_EQ(scene.meshes.size(), 1u);
  const Mesh& m = scene.meshes[0];
  ASSERT_EQ(m.triangleCount(), 6u);
  EXPECT_EQ(m.faceGroups, groups);
  EXPECT_EQ(m.faceMaterials, materials);
  EXPECT_EQ(scene.instanceNames, (std::vector<std::string>{"room", "chair", "table top"}));
  EXPECT_EQ(scene.meshNames, (std::vector<std::string>{"room"}));
  EXPECT_EQ(scene.materialNames, (std::vector<std::string>{"red", "blue", "default"}));
  ASSERT_EQ(scene.instances.size(), 1u);
  EXPECT_EQ(scene.instances[0].mesh, 0u);
  EXPECT_EQ(scene.instances[0].id, 0u);
  EXPECT_EQ(scene.instances[0].worldFromMesh, glm::dmat4(1.0));

  // Every corner: the position and the texture coordinate (u, 1 - v) it was written with,
  // triangles in file order; a (v, vt) pair is one vertex, distinct pairs distinct vertices.
  ASSERT_EQ(m.texcoords.size(), 2 * m.vertexCount);
  ASSERT_EQ(m.positionsDouble.size(), 3 * m.vertexCount);
  std::map<std::pair<int, int>, uint32_t> vertexOfPair;
  for (size_t c = 0; c < corners.size(); ++c) {
    const uint32_t k = m.indices[c];
    ASSERT_LT(k, m.vertexCount);
    const auto [p, t] = corners[c];
    for (int a = 0; a < 3; ++a) EXPECT_EQ(m.positionsDouble[3 * k + a], v[p - 1][a]) << c;
    EXPECT_EQ(m.texcoords[2 * k], float(vt[t - 1][0])) << c;
    EXPECT_EQ(m.texcoords[2 * k + 1], float(1.0 - vt[t - 1][1])) << c;
    const auto [it, fresh] = vertexOfPair.emplace(corners[c], k);
    EXPECT_EQ(it->second, k) << "corner " << c << " does not share its pair's vertex";
  }
  std::set<uint32_t> distinct;
  for (const auto& [pair, k] : vertexOfPair) distinct.insert(k);
  EXPECT_EQ(distinct.size(), vertexOfPair.size());
  EXPECT_EQ(m.vertexCount, 8u);  // the 8 distinct pairs; no vertex without a corner

  // Materials: Kd as written, the default white, red's texture beside the .mtl.
  ASSERT_EQ(scene.materials.size(), 3u);
  EXPECT_EQ(scene.materials[0].name, "red");
  EXPECT_EQ(scene.materials[0].baseColor, glm::vec4(0.8f, 0.1f, 0.2f, 1.0f));
  EXPECT_EQ(scene.materials[1].name, "blue");
  EXPECT_EQ(scene.materials[1].baseColor, glm::vec4(0.1f, 0.2f, 0.9f, 1.0f));
  EXPECT_EQ(scene.materials[1].baseColorTexture, -1);
  EXPECT_EQ(scene.materials[2].name, "default");
  EXPECT_EQ(scene.materials[2].baseColor, glm::vec4(1.0f));
  EXPECT_EQ(scene.materials[2].baseColorTexture, -1);
  ASSERT_EQ(scene.textures.size(), 1u);
  EXPECT_EQ(scene.materials[0].baseColorTexture, 0);
  const SurfaceTexture& tex = scene.textures[0];
  EXPECT_EQ(tex.where, dir + "/room.mtl:4");
  EXPECT_EQ(tex.path, dir + "/textures/red.png");
  EXPECT_EQ(tex.wrapS, TextureWrap::Repeat);
  EXPECT_EQ(tex.wrapT, TextureWrap::Repeat);
  EXPECT_TRUE(tex.srgb);
  EXPECT_FALSE(tex.nearest);
  EXPECT_TRUE(tex.bytes.empty());
}

TEST(ObjScene, NamesWithoutAskingForIdsAndNoDefaults) {
  const std::string dir = sceneDir("obj_scene_names");
  const SceneFile room = loadObjScene(writeRoom(dir), {});
  EXPECT_TRUE(room.meshes[0].faceGroups.empty());
  EXPECT_TRUE(room.meshes[0].faceMaterials.empty());
  EXPECT_TRUE(room.meshes[0].texcoords.empty());
  EXPECT_EQ(room.meshes[0].vertexCount, 5u);  // no split without texcoords
  EXPECT_EQ(room.instanceNames, (std::vector<std::string>{"room", "chair", "table top"}));
  EXPECT_EQ(room.materialNames, (std::vector<std::string>{"red", "blue", "default"}));

  // Every face after an o and a usemtl: no object named after the file, no "default"; a
  // material no library defines is white; a vertex used with one vt only is not split.
  test::writeFile(dir + "/plain.obj",
                  "o a\nusemtl nowhere\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.25\n"
                  "f 1/1 2/1 3/1\ng b\nf 3/1 2/1 1/1\n");
  const SceneFile plain = loadObjScene(dir + "/plain.obj", everything());
  EXPECT_EQ(plain.instanceNames, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(plain.materialNames, (std::vector<std::string>{"nowhere"}));
  ASSERT_EQ(plain.materials.size(), 1u);
  EXPECT_EQ(plain.materials[0].baseColor, glm::vec4(1.0f));
  EXPECT_EQ(plain.meshes[0].faceGroups, (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(plain.meshes[0].faceMaterials, (std::vector<uint32_t>{0, 0}));
  EXPECT_EQ(plain.meshes[0].vertexCount, 3u);
  EXPECT_EQ(plain.meshes[0].texcoords, (std::vector<float>{0.5f, 0.75f, 0.5f, 0.75f, 0.5f, 0.75f}));
}

TEST(ObjScene, LoadObjKeepsGeometryAndAsksNoLibrary) {
  // loadObj reads the same ids when asked, and never opens the .mtl (there is none here).
  const std::string dir = sceneDir("obj_scene_plain_load");
  test::writeFile(dir + "/room.obj", kRoomObj);
  const Mesh m = loadObj(dir + "/room.obj", everything());
  EXPECT_EQ(m.faceGroups, (std::vector<uint32_t>{0, 1, 2, 2, 1, 1}));
  EXPECT_EQ(m.faceMaterials, (std::vector<uint32_t>{2, 0, 0, 0, 1, 0}));
  EXPECT_EQ(m.vertexCount, 8u);
  // Its .mtl is missing: an error only where the materials are asked for (material, albedo).
  EXPECT_EQ(loadObjScene(dir + "/room.obj").materialNames.size(), 3u);
  EXPECT_NE(test::errorOf([&] { loadObjScene(dir + "/room.obj", everything()); }), "");
}

TEST(ObjScene, MissingLibraryNamesTheObjLineAndThePathTried) {
  const std::string dir = sceneDir("obj_scene_no_mtl");
  test::writeFile(dir + "/t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nmtllib here.mtl gone.mtl\nf 1 2 3\n");
  test::writeFile(dir + "/here.mtl", "newmtl x\nKd 1 0 0\n");
  const std::string message = test::errorOf([&] { loadObjScene(dir + "/t.obj", everything()); });
  EXPECT_NE(message.find(dir + "/t.obj:4"), std::string::npos) << message;
  EXPECT_NE(message.find(dir + "/gone.mtl"), std::string::npos) << message;
}

TEST(ObjScene, MissingTextureNamesTheMtlLine) {
  const std::string dir = sceneDir("obj_scene_no_texture");
  test::writeFile(dir + "/t.obj", "mtllib m/t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n");
  std::filesystem::create_directories(dir + "/m");
  test::writeFile(dir + "/m/t.mtl", "newmtl x\nKd 1 0 0\nmap_Kd gone.png\n");
  const std::string message = test::errorOf([&] { loadObjScene(dir + "/t.obj", everything()); });
  EXPECT_NE(message.find(dir + "/m/t.mtl:3"), std::string::npos) << message;
  EXPECT_NE(message.find(dir + "/m/gone.png"), std::string::npos) << message;
  // A malformed Kd: the .mtl and its line.
  test::writeFile(dir + "/m/t.mtl", "newmtl x\n\nKd 1 x 0\n");
  const std::string kd = test::errorOf([&] { loadObjScene(dir + "/t.obj", everything()); });
  EXPECT_NE(kd.find(dir + "/m/t.mtl:3"), std::string::npos) << kd;
}

TEST(ObjScene, MappingOptionsAreRefusedByName) {
  const std::string dir = sceneDir("obj_scene_option");
  test::writeFile(dir + "/tex.png", "x");
  test::writeFile(dir + "/t.obj", "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n");
  for (const std::string option : {"-s 2 2 1", "-o 0.5", "-t 0.1 0.1"}) {
    test::writeFile(dir + "/t.mtl", "newmtl x\nmap_Kd " + option + " tex.png\n");
    const std::string message = test::errorOf([&] { loadObjScene(dir + "/t.obj", everything()); });
    const std::string name = option.substr(0, 2);
    EXPECT_NE(message.find(dir + "/t.mtl:2"), std::string::npos) << message;
    EXPECT_NE(message.find("'" + name + "'"), std::string::npos) << message;
  }
  // -clamp on is read (ClampToEdge), -blendu ignored.
  test::writeFile(dir + "/t.mtl", "newmtl x\nmap_Kd -clamp on -blendu off tex.png\n");
  const SceneFile scene = loadObjScene(dir + "/t.obj", everything());
  ASSERT_EQ(scene.textures.size(), 1u);
  EXPECT_EQ(scene.textures[0].path, dir + "/tex.png");
  EXPECT_EQ(scene.textures[0].wrapS, TextureWrap::ClampToEdge);
}

TEST(ObjScene, CornerWithoutTexcoordAmongOthersIsAnError) {
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1/1 2 3/1\n";
  const std::string message =
      test::errorOf([&] { loadObjSceneFromMemory(obj.data(), obj.size(), "t.obj", everything()); });
  EXPECT_NE(message.find("t.obj:6"), std::string::npos) << message;
  // Without texcoords asked for, the vt indices are not read.
  EXPECT_EQ(test::errorOf([&] { loadObjSceneFromMemory(obj.data(), obj.size(), "t.obj"); }), "");
}

TEST(ObjScene, SharedSpotMatchesLoadObj) {
  APERTURE_REQUIRE_SHARED_MESH(path, "obj/spot.obj");
  const Mesh plain = loadObj(path);
  const SceneFile scene = loadObjScene(path, everything());
  const Mesh& m = scene.meshes[0];
  ASSERT_EQ(m.triangleCount(), plain.triangleCount());
  for (size_t c = 0; c < m.indices.size(); ++c)
    for (size_t a = 0; a < 3; ++a)
      ASSERT_EQ(m.positionsDouble[3 * size_t(m.indices[c]) + a],
                plain.positionsDouble[3 * size_t(plain.indices[c]) + a])
          << "corner " << c;
  // Independently: one vertex per distinct "v/vt" corner token of the faces.
  std::ifstream in(path);
  std::set<std::string> pairs;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("f ", 0) != 0) continue;
    std::istringstream tokens(line.substr(2));
    std::string corner;
    while (tokens >> corner) pairs.insert(corner.substr(0, corner.find('/', corner.find('/') + 1)));
  }
  EXPECT_EQ(m.vertexCount, pairs.size());
  EXPECT_EQ(m.texcoords.size(), 2 * pairs.size());
  EXPECT_EQ(scene.instanceNames, (std::vector<std::string>{"spot"}));
}

}  // namespace
}  // namespace aperture
