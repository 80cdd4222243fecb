// glTF scenes through the command line (issue 41): the test scene as .gltf + .bin, .glb, Draco
// and meshopt renders the same pixels bit for bit; every pixel's instance, mesh, material and
// primid are those of the triangle a brute-force trace of its ray meets first (the world
// triangles composed here from the writer's nodes, not by the loader); the names behind the
// ids in the EXR header and summary.json; a mesh placed by three nodes built once; a job
// placing a GLB like a PLY (its transform moves the whole file); bad files refused with the
// file and a JSON pointer and nothing written; visibility over a glTF; an OBJ's objects and
// materials numbered after a PLY placed before it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/exr/exr.h"
#include "core/util/error.h"
#include "tests/gltf_support.h"
#include "tests/job_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using nlohmann::json;

/// One triangle of the scene in world space, with the glTF indices it stands for.
struct WorldTriangle {
  glm::dvec3 a, b, c;
  uint32_t node, mesh, material, prim;
};

void addNodeTriangles(const test::GltfScene& s, int node, const glm::dmat4& parent,
                      std::vector<WorldTriangle>& out) {
  const test::GltfNode& n = s.nodes[size_t(node)];
  const glm::dmat4 world = parent * test::gltfLocalMatrix(n);
  if (n.mesh >= 0) {
    uint32_t prim = 0;
    for (const test::GltfPrimitive& p : s.meshes[size_t(n.mesh)].primitives) {
      const auto at = [&](uint32_t v) {
        return glm::dvec3(world * glm::dvec4(p.positions[3 * v], p.positions[3 * v + 1],
                                             p.positions[3 * v + 2], 1.0));
      };
      for (size_t t = 0; t + 2 < p.indices.size(); t += 3)
        out.push_back({at(p.indices[t]), at(p.indices[t + 1]), at(p.indices[t + 2]), uint32_t(node),
                       uint32_t(n.mesh), uint32_t(p.material), prim++});
      if (p.indices.empty())
        for (uint32_t v = 0; v + 2 < p.positions.size() / 3; v += 3)
          out.push_back({at(v), at(v + 1), at(v + 2), uint32_t(node), uint32_t(n.mesh),
                         uint32_t(p.material), prim++});
    }
  }
  for (int child : n.children) addNodeTriangles(s, child, world, out);
}

/// The scene's triangles in world space, each placed by `placement` too.
std::vector<WorldTriangle> worldTriangles(const test::GltfScene& s,
                                          const glm::dmat4& placement = glm::dmat4(1.0)) {
  std::vector<WorldTriangle> out;
  for (int root : s.roots) addNodeTriangles(s, root, placement, out);
  return out;
}

/// The first triangle the ray o + t d (t > 0) meets, or null; `clear` is false when the hit
/// lies within `margin` (barycentric) of an edge, or another triangle is hit at nearly the
/// same t, where a float renderer may see either.
const WorldTriangle* firstHit(const std::vector<WorldTriangle>& tris, const glm::dvec3& o,
                              const glm::dvec3& d, double& tHit, bool& clear) {
  const WorldTriangle* best = nullptr;
  double second = INFINITY;
  tHit = INFINITY;
  clear = true;
  bool bestClear = true;
  for (const WorldTriangle& tri : tris) {
    const glm::dvec3 e1 = tri.b - tri.a, e2 = tri.c - tri.a, p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-14) continue;
    const glm::dvec3 s = o - tri.a;
    const double u = glm::dot(s, p) / det;
    const glm::dvec3 q = glm::cross(s, e1);
    const double v = glm::dot(d, q) / det, t = glm::dot(e2, q) / det;
    constexpr double margin = 1e-3;
    if (u < -margin || v < -margin || u + v > 1 + margin || t <= 0) continue;
    const bool inside = u > margin && v > margin && u + v < 1 - margin;
    if (t < tHit) {
      second = tHit;
      tHit = t, best = &tri, bestClear = inside;
    } else {
      second = std::min(second, t);
    }
  }
  clear = best && bestClear && second - tHit > 1e-4 * tHit;
  return best;
}

struct GltfRendered {
  Framebuffer fb;
  ExrMetadata meta;
};

constexpr const char* kAovs = "depth,normal,position,primid,geomid,instance,mesh,material";

GltfRendered renderFile(const std::string& mesh, const std::string& view, const std::string& out) {
  std::string log;
  const int code =
      test::runCommand(test::apertureBinary() + " render --quiet --mesh " + test::quote(mesh) +
                           " " + view + " --aov " + kAovs + " --out " + test::quote(out),
                       &log);
  EXPECT_EQ(code, 0) << log;
  GltfRendered r;
  if (code == 0) r.fb = readExr(out, &r.meta);
  return r;
}

/// The view of the whole test scene: at its box's centre from in front of it.
std::string sceneView(const std::vector<WorldTriangle>& tris, glm::dvec3* eyeOut) {
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const WorldTriangle& t : tris)
    for (const glm::dvec3& p : {t.a, t.b, t.c}) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double size = glm::length(hi - lo);
  const glm::dvec3 eye = centre + size * glm::dvec3(0.3, 0.5, 1.2);
  *eyeOut = eye;
  return cat("--eye ", eye.x, ",", eye.y, ",", eye.z, " --at ", centre.x, ",", centre.y, ",",
             centre.z, " --fov 50 --size 192,144");
}

/// Checks every clear pixel's ids against the first triangle its ray meets; returns how many
/// pixels each node was seen in.
std::map<uint32_t, int> checkIdsByBruteForce(const Framebuffer& fb,
                                             const std::vector<WorldTriangle>& tris,
                                             const glm::dvec3& eye, uint32_t instanceBase = 0) {
  std::map<uint32_t, int> seen;
  for (size_t px = 0; px < fb.pixelCount(); ++px) {
    if (!std::isfinite(fb.depth[px])) {
      EXPECT_EQ(fb.instanceId[px], kInvalidId) << px;
      EXPECT_EQ(fb.meshId[px], kInvalidId) << px;
      EXPECT_EQ(fb.materialId[px], kInvalidId) << px;
      continue;
    }
    const glm::dvec3 p(fb.position[3 * px], fb.position[3 * px + 1], fb.position[3 * px + 2]);
    double t = 0;
    bool clear = false;
    const WorldTriangle* hit = firstHit(tris, eye, glm::normalize(p - eye), t, clear);
    if (!hit || !clear) continue;
    EXPECT_NEAR(t, glm::length(p - eye), 1e-4 * t) << px;
    EXPECT_EQ(fb.instanceId[px], instanceBase + hit->node) << px;
    EXPECT_EQ(fb.meshId[px], hit->mesh) << px;
    EXPECT_EQ(fb.materialId[px], hit->material) << px;
    EXPECT_EQ(fb.primId[px], hit->prim) << px;
    ++seen[hit->node];
  }
  return seen;
}

const std::vector<std::string>* stringVector(const ExrMetadata& meta, const std::string& name) {
  for (const auto& [key, values] : meta.stringVectors)
    if (key == name) return &values;
  return nullptr;
}

std::vector<std::string> nodeNames(const test::GltfScene& s) {
  std::vector<std::string> names;
  for (const test::GltfNode& n : s.nodes) names.push_back(n.name);
  return names;
}

TEST(GltfScenesCli, EveryEncodingRendersTheSamePixelsAndTheIdsOfTheTriangleSeen) {
  const std::string dir = test::scratchDir();
  const test::GltfScene scene = test::issue41Scene();
  const std::vector<WorldTriangle> tris = worldTriangles(scene);
  glm::dvec3 eye;
  const std::string view = sceneView(tris, &eye);
  const GltfRendered gltf =
      renderFile(test::writeGltf(scene, dir + "/scene.gltf"), view, dir + "/gltf.exr");
  ASSERT_FALSE(gltf.fb.depth.empty());
  const std::map<uint32_t, int> seen = checkIdsByBruteForce(gltf.fb, tris, eye);
  for (const uint32_t node : {1u, 2u, 4u, 5u})
    EXPECT_GT(seen.count(node) ? seen.at(node) : 0, 10)
        << "node " << node << " is hardly seen: the test does not check it";
  // The names behind the ids: the file's nodes, meshes and materials, by index.
  const std::vector<std::string>* instances = stringVector(gltf.meta, "aperture.instanceNames");
  ASSERT_NE(instances, nullptr);
  EXPECT_EQ(*instances, nodeNames(scene));
  const std::vector<std::string>* meshes = stringVector(gltf.meta, "aperture.meshNames");
  ASSERT_NE(meshes, nullptr);
  EXPECT_EQ(*meshes, (std::vector<std::string>{"quad", "tri"}));
  const std::vector<std::string>* materials = stringVector(gltf.meta, "aperture.materialNames");
  ASSERT_NE(materials, nullptr);
  EXPECT_EQ(*materials, (std::vector<std::string>{"checker", "red"}));

  const std::pair<const char*, test::GltfCompression> others[] = {
      {"scene.glb", test::GltfCompression::None},
      {"draco.glb", test::GltfCompression::Draco},
      {"meshopt.glb", test::GltfCompression::Meshopt}};
  for (const auto& [name, compression] : others) {
    const GltfRendered r = renderFile(test::writeGltf(scene, dir + "/" + name, compression), view,
                                      dir + "/" + name + ".exr");
    test::expectIdentical(r.fb, gltf.fb, name);
  }
}

TEST(GltfScenesCli, OnlyTheIdAovsWrittenNameTheirIds) {
  const std::string dir = test::scratchDir();
  const test::GltfScene scene = test::issue41Scene();
  glm::dvec3 eye;
  const std::string view = sceneView(worldTriangles(scene), &eye);
  const std::string out = dir + "/mesh.exr";
  std::string log;
  ASSERT_EQ(test::runCommand(test::apertureBinary() + " render --quiet --mesh " +
                                 test::quote(test::writeGltf(scene, dir + "/s.glb")) + " " + view +
                                 " --aov depth,mesh --out " + test::quote(out),
                             &log),
            0)
      << log;
  ExrMetadata meta;
  readExr(out, &meta);
  EXPECT_NE(stringVector(meta, "aperture.meshNames"), nullptr);
  EXPECT_EQ(stringVector(meta, "aperture.instanceNames"), nullptr);
  EXPECT_EQ(stringVector(meta, "aperture.materialNames"), nullptr);
}

TEST(GltfScenesCli, AJobPlacesAGlbLikeAPlyAndTheSummaryNamesTheIds) {
  const std::string dir = test::scratchDir();
  const test::GltfScene scene = test::issue41Scene();
  const std::string glb = test::writeGltf(scene, dir + "/scene.glb");
  // The job's transform: translate, rotate about z by 30 degrees, scale 1.5, applied to the
  // whole file (its root nodes).
  glm::dmat4 placement = glm::translate(glm::dmat4(1.0), glm::dvec3(4, -2, 1));
  placement = glm::rotate(placement, glm::radians(30.0), glm::dvec3(0, 0, 1));
  placement = glm::scale(placement, glm::dvec3(1.5));
  const std::vector<WorldTriangle> tris = worldTriangles(scene, placement);
  glm::dvec3 eye;
  sceneView(tris, &eye);
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const WorldTriangle& t : tris)
    for (const glm::dvec3& p : {t.a, t.b, t.c}) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const glm::dvec3 at = 0.5 * (lo + hi);
  json job = {
      {"scene",
       {{"meshes",
         {{{"path", "scene.glb"},
           {"transform",
            {{"translate", {4, -2, 1}},
             {"rotate", {{"axis", {0, 0, 1}}, {"angle", 30}}},
             {"scale", 1.5}}}}}}}},
      {"cameras",
       {{{"name", "c"}, {"eye", {eye.x, eye.y, eye.z}}, {"at", {at.x, at.y, at.z}}, {"fov", 50}}}},
      {"size", {96, 72}},
      {"aovs", {"depth", "position", "primid", "instance", "mesh", "material"}},
      {"id_counts", true},
      {"output", "out/{camera}.exr"}};
  const std::string jobPath = test::writeJob(dir, job);
  std::string log;
  ASSERT_EQ(test::runBatch("--quiet", jobPath, &log), 0) << log;
  ExrMetadata meta;
  const Framebuffer fb = readExr(dir + "/out/c.exr", &meta);
  // The transform composes as documented: translate · rotate · scale.
  const std::map<uint32_t, int> seen = checkIdsByBruteForce(fb, tris, eye);
  EXPECT_GE(seen.size(), 3u);
  const json summary = test::readJson(dir + "/out/summary.json");
  ASSERT_TRUE(summary.contains("ids")) << summary.dump(1);
  EXPECT_EQ(summary["ids"]["instance"].get<std::vector<std::string>>(), nodeNames(scene));
  EXPECT_EQ(summary["ids"]["mesh"].get<std::vector<std::string>>(),
            (std::vector<std::string>{"quad", "tri"}));
  EXPECT_EQ(summary["ids"]["material"].get<std::vector<std::string>>(),
            (std::vector<std::string>{"checker", "red"}));
  // The quad placed by three nodes is stored and built once.
  EXPECT_EQ(summary["triangles"].get<size_t>(), 3u * 2 + 1);
  EXPECT_EQ(summary["unique_triangles"].get<size_t>(), 2u + 1);
  // id_counts counts the scene-wide ids as the EXR holds them.
  const json& counts = summary["images"][0]["id_counts"];
  for (const auto& [aov, values] :
       {std::pair<std::string, const std::vector<uint32_t>*>{"instance", &fb.instanceId},
        {"mesh", &fb.meshId},
        {"material", &fb.materialId}}) {
    std::map<std::string, uint64_t> want;
    for (uint32_t id : *values)
      if (id != kInvalidId) ++want[std::to_string(id)];
    ASSERT_TRUE(counts.contains(aov)) << counts.dump();
    EXPECT_EQ(counts[aov].get<decltype(want)>(), want) << aov;
  }
}

TEST(GltfScenesCli, AGlbPlacedTwiceNumbersTheSecondPlacementsInstancesAfterTheFirst) {
  const std::string dir = test::scratchDir();
  const test::GltfScene scene = test::issue41Scene();
  test::writeGltf(scene, dir + "/scene.glb");
  json job = {{"scene",
               {{"meshes",
                 {{{"path", "scene.glb"}},
                  {{"path", "scene.glb"}, {"transform", {{"translate", {40, 0, 0}}}}}}}}},
              {"cameras", {{{"name", "c"}, {"eye", {20, 5, 60}}, {"at", {20, 0, 0}}}}},
              {"size", {32, 24}},
              {"aovs", {"depth", "instance"}},
              {"output", "out/{camera}.exr"}};
  std::string log;
  ASSERT_EQ(test::runBatch("--quiet", test::writeJob(dir, job), &log), 0) << log;
  const json summary = test::readJson(dir + "/out/summary.json");
  std::vector<std::string> twice = nodeNames(scene);
  const std::vector<std::string> once = twice;
  twice.insert(twice.end(), once.begin(), once.end());
  EXPECT_EQ(summary["ids"]["instance"].get<std::vector<std::string>>(), twice);
  EXPECT_FALSE(summary["ids"].contains("mesh"));
  // Every mesh is placed several times now: each stored once.
  EXPECT_EQ(summary["triangles"].get<size_t>(), 2u * 7);
  EXPECT_EQ(summary["unique_triangles"].get<size_t>(), 3u);
}

TEST(GltfScenesCli, ABadFileIsRefusedWithItsJsonPointerAndNothingIsWritten) {
  const std::string dir = test::scratchDir();
  const std::string path = test::writeGltf(test::issue41Scene(), dir + "/bad.gltf");
  test::editGltf(path, [](json& j) { j["accessors"][0]["count"] = 1000000; });
  const std::string out = dir + "/bad.exr";
  std::string log;
  const int code = test::runCommand(test::apertureBinary() + " render --mesh " + test::quote(path) +
                                        " --aov depth,instance --out " + test::quote(out),
                                    &log);
  EXPECT_EQ(code, 1) << log;
  EXPECT_NE(log.find(path), std::string::npos) << log;
  EXPECT_NE(log.find("/accessors/0"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(out));
}

/// A COLMAP text model of one pinhole camera at (0, 0, -10) looking along +z.
std::string frontCameraModel(const std::string& dir) {
  std::filesystem::create_directories(dir);
  test::writeFile(dir + "/cameras.txt", "1 PINHOLE 64 48 60 60 32 24\n");
  test::writeFile(dir + "/images.txt", "1 1 0 0 0 0 0 10 1 front.png\n\n");
  return dir;
}

TEST(GltfScenesCli, VisibilityTakesAGltfOfOneMeshAndRefusesSeveral) {
  const std::string dir = test::scratchDir();
  const std::string model = frontCameraModel(dir + "/sparse");
  // One quad placed by one node: the same faces as the PLY of its triangles.
  test::GltfScene one;
  test::GltfPrimitive quad;
  quad.positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  quad.indices = {0, 1, 2, 0, 2, 3};
  one.meshes = {{"quad", {quad}}};
  one.nodes.resize(1);
  one.nodes[0].mesh = 0;
  one.roots = {0};
  test::writeFile(dir + "/quad.ply",
                  "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float "
                  "y\nproperty float z\nelement face 2\nproperty list uchar int "
                  "vertex_indices\nend_header\n-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n3 0 1 2\n3 0 2 "
                  "3\n");
  std::string log;
  for (const std::string& mesh : {test::writeGltf(one, dir + "/quad.glb"), dir + "/quad.ply"})
    ASSERT_EQ(test::runCommand(test::apertureBinary() + " visibility --quiet --mesh " +
                                   test::quote(mesh) + " --cameras " + test::quote(model) +
                                   " --out " + test::quote(mesh + ".npz"),
                               &log),
              0)
        << log;
  EXPECT_EQ(test::readFile(dir + "/quad.glb.npz"), test::readFile(dir + "/quad.ply.npz"));
  const std::string several = test::writeGltf(test::issue41Scene(), dir + "/scene.glb");
  const int code = test::runCommand(test::apertureBinary() + " visibility --quiet --mesh " +
                                        test::quote(several) + " --cameras " + test::quote(model) +
                                        " --out " + test::quote(dir + "/several.npz"),
                                    &log);
  EXPECT_EQ(code, 1) << log;
  EXPECT_NE(log.find("the scene places 4 meshes (quad_a, quad_b, quad_c, tri)"), std::string::npos)
      << log;
  EXPECT_FALSE(std::filesystem::exists(dir + "/several.npz"));
}

TEST(SceneFilesCli, ObjObjectsAndMaterialsAreNumberedAfterThePlacementsBefore) {
  const std::string dir = test::scratchDir();
  test::writeFile(dir + "/left.ply",
                  "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float "
                  "y\nproperty float z\nelement face 1\nproperty list uchar int "
                  "vertex_indices\nend_header\n-5 -1 0\n-3 -1 0\n-3 1 0\n-5 1 0\n4 0 1 2 3\n");
  test::writeFile(dir + "/objs.mtl", "newmtl m1\nKd 1 0 0\nnewmtl m2\nKd 0 1 0\n");
  test::writeFile(dir + "/objs.obj",
                  "mtllib objs.mtl\no a\nusemtl m1\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                  "f 1 2 3 4\no b\nusemtl m2\nv 3 -1 0\nv 5 -1 0\nv 5 1 0\nv 3 1 0\nf 5 6 7 8\n");
  const std::string out = dir + "/ids.exr";
  std::string log;
  ASSERT_EQ(test::runCommand(test::apertureBinary() + " render --quiet --mesh " +
                                 test::quote(dir + "/left.ply") + " --mesh " +
                                 test::quote(dir + "/objs.obj") +
                                 " --eye 0,0,12 --at 0,0,0 --fov 60 --size 120,40 --aov "
                                 "position,instance,mesh,material,albedo --out " +
                                 test::quote(out),
                             &log),
            0)
      << log;
  ExrMetadata meta;
  const Framebuffer fb = readExr(out, &meta);
  struct Expected {
    double lo, hi;
    uint32_t instance, mesh, material;
    glm::vec4 albedo;
  };
  const Expected regions[] = {{-4.9, -3.1, 0, 0, 0, glm::vec4(1)},  // the PLY: its "default"
                              {-0.9, 0.9, 1, 1, 1, glm::vec4(1, 0, 0, 1)},
                              {3.1, 4.9, 2, 1, 2, glm::vec4(0, 1, 0, 1)}};
  int checked[3] = {0, 0, 0};
  for (size_t px = 0; px < fb.pixelCount(); ++px) {
    if (fb.instanceId[px] == kInvalidId) continue;
    const double x = fb.position[3 * px];
    for (int r = 0; r < 3; ++r) {
      const Expected& e = regions[r];
      if (x < e.lo || x > e.hi) continue;
      EXPECT_EQ(fb.instanceId[px], e.instance) << px;
      EXPECT_EQ(fb.meshId[px], e.mesh) << px;
      EXPECT_EQ(fb.materialId[px], e.material) << px;
      for (int c = 0; c < 4; ++c) EXPECT_EQ(fb.albedo[4 * px + c], e.albedo[c]) << px;
      ++checked[r];
    }
  }
  for (int r = 0; r < 3; ++r) EXPECT_GT(checked[r], 20) << r;
  EXPECT_EQ(*stringVector(meta, "aperture.instanceNames"),
            (std::vector<std::string>{"left", "a", "b"}));
  EXPECT_EQ(*stringVector(meta, "aperture.meshNames"), (std::vector<std::string>{"left", "objs"}));
  EXPECT_EQ(*stringVector(meta, "aperture.materialNames"),
            (std::vector<std::string>{"default", "m1", "m2"}));
}

}  // namespace
}  // namespace aperture
