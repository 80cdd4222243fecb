// View-volume culling (issue 5, item 8): the BVH holds only the triangles the cameras may see,
// and every AOV is bit-identical with and without culling.
#include <gtest/gtest.h>

#include <cstring>
#include <deque>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <vector>

#include "cameras/registry/culling.h"
#include "cameras/registry/registry.h"
#include "core/engine/cull.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/exr/exr.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// Culled and full scenes over the same objects, for `cameras`.
struct CulledPair {
  std::deque<TriangleSubset> subsets;
  std::unique_ptr<Scene> full, culled;
  CullStats stats;
};

std::unique_ptr<CulledPair> cullFor(std::vector<SceneObject> objects,
                                    const std::vector<CameraParams>& cameras,
                                    const BuildOptions& bo = {}) {
  auto pair = std::make_unique<CulledPair>();
  pair->full = std::make_unique<Scene>(test::numericsDevice(), objects, bo);
  const CameraCuller culler = cullerFor(cameras, pair->full->renderOrigin());
  pair->stats = cullObjects(objects, culler.test(), pair->subsets);
  pair->culled = std::make_unique<Scene>(test::numericsDevice(), objects, bo);
  return pair;
}

CameraParams closeUp(const char* type = "perspective") {
  CameraParams p;
  p.type = type;
  p.eye = glm::dvec3(-3.0, 1.5, 4.0);
  p.at = glm::dvec3(-5.6, 1.0, -2.5);
  p.width = 120;
  p.height = 80;
  p.fovDeg = 35;
  return p;
}

std::vector<CameraParams> cameraKinds() {
  std::vector<CameraParams> all;
  all.push_back(closeUp());
  CameraParams lens = closeUp("thinlens");
  lens.apertureRadius = 0.3;
  lens.focusDistance = 6.0;
  lens.spp = 4;
  all.push_back(lens);
  CameraParams shifted = closeUp();
  shifted.shift = glm::dvec2(0.4, -0.3);
  all.push_back(shifted);
  CameraParams ortho = closeUp("orthographic");
  ortho.viewport = glm::dvec2(3.0, 2.0);
  all.push_back(ortho);
  CameraParams oblique = closeUp("oblique");
  oblique.viewport = glm::dvec2(3.0, 2.0);
  oblique.obliqueAnglesDeg = glm::dvec2(30.0, -20.0);
  all.push_back(oblique);
  CameraParams wide = closeUp();
  wide.eye = glm::dvec3(30, 25, 30);
  wide.at = glm::dvec3(0.0);
  wide.fovDeg = 5;
  all.push_back(wide);
  return all;
}

TEST(CullingCity, EveryAovIsBitIdenticalForEveryCameraKind) {
  const Mesh city = loadMesh("procedural:city");
  for (const CameraParams& p : cameraKinds()) {
    for (bool robust : {false, true}) {
      BuildOptions bo;
      bo.robust = robust;
      const auto pair = cullFor({{&city, glm::dmat4(1.0), nullptr}}, {p}, bo);
      EXPECT_LT(pair->stats.trianglesKept, city.triangleCount()) << p.type;
      EXPECT_GT(pair->stats.trianglesKept, 0u) << p.type;
      EXPECT_EQ(pair->culled->stats().triangles + pair->culled->stats().culledTriangles,
                city.triangleCount());
      EXPECT_TRUE(pair->culled->remapsPrimIds());
      test::expectIdentical(test::render(*pair->culled, p), test::render(*pair->full, p), p.type);
    }
  }
}

TEST(CullingCity, TheUnionOfSeveralCamerasServesEachOfThem) {
  const Mesh city = loadMesh("procedural:city");
  const std::vector<CameraParams> cams = cameraKinds();
  const auto pair = cullFor({{&city, glm::dmat4(1.0), nullptr}}, cams);
  for (const CameraParams& p : cams)
    test::expectIdentical(test::render(*pair->culled, p), test::render(*pair->full, p), p.type);
}

TEST(CullingCity, FarFromTheOriginInWorldSpaceTheOriginRoundingIsCovered) {
  LoadOptions lo;
  lo.placement = Placement::WorldSpace;
  lo.translate = glm::dvec3(3e5, 0.0, -2e5);
  const Mesh city = loadMesh("procedural:city", lo);
  CameraParams p = closeUp();
  p.eye += lo.translate;
  *p.at += lo.translate;
  const auto pair = cullFor({{&city, glm::dmat4(1.0), nullptr}}, {p});
  EXPECT_LT(pair->stats.trianglesKept, city.triangleCount());
  test::expectIdentical(test::render(*pair->culled, p), test::render(*pair->full, p),
                        "world-space");
}

TEST(CullingCity, InstancedPlacementsKeepTheUnionAndReportOriginalPrimIds) {
  const Mesh city = loadMesh("procedural:city");
  const glm::dmat4 moved = glm::translate(glm::dmat4(1.0), glm::dvec3(40.0, 0.0, 0.0));
  CameraParams p = closeUp();
  p.eye += glm::dvec3(40, 0, 0);
  *p.at += glm::dvec3(40, 0, 0);
  const auto pair =
      cullFor({{&city, glm::dmat4(1.0), nullptr}, {&city, moved, nullptr}}, {p, closeUp()});
  EXPECT_EQ(pair->culled->instanceCount(), 2u);
  EXPECT_LT(pair->stats.trianglesKept, city.triangleCount());
  test::expectIdentical(test::render(*pair->culled, p), test::render(*pair->full, p), "instance 1");
  test::expectIdentical(test::render(*pair->culled, closeUp()),
                        test::render(*pair->full, closeUp()), "instance 0");
}

TEST(CullingCity, PanoramasSeeEverything) {
  CameraParams pano;
  pano.type = "equirect";
  pano.width = 64;
  pano.height = 32;
  const CameraCuller c = cullerFor({closeUp(), pano}, glm::dvec3(0.0));
  EXPECT_TRUE(c.seesEverything);
  EXPECT_TRUE(c.mayIntersectBox(glm::dvec3(1e9), glm::dvec3(1e9 + 1)));
  const CameraCuller persp = cullerFor({closeUp()}, glm::dvec3(0.0));
  EXPECT_FALSE(persp.seesEverything);
  EXPECT_FALSE(persp.mayIntersectBox(glm::dvec3(1e3), glm::dvec3(1e3 + 1)));  // behind it
  EXPECT_THROW(cullerFor({}, glm::dvec3(0.0)), Error);
}

TEST(CullingCity, AnObjectWithNothingKeptLeavesItsGeomIdUnused) {
  const Mesh city = loadMesh("procedural:city");
  const Mesh far = loadMesh("procedural:sphere?cx=500");
  std::vector<SceneObject> objects{{&city, glm::dmat4(1.0), nullptr},
                                   {&far, glm::dmat4(1.0), nullptr}};
  // Share one anchor so both attach directly.
  Mesh farMoved = far;
  const glm::dvec3 delta = far.anchor - city.anchor;
  for (size_t v = 0; v < farMoved.vertexCount; ++v)
    for (int c = 0; c < 3; ++c)
      farMoved.positions[3 * v + size_t(c)] =
          float(farMoved.positions[3 * v + size_t(c)] + delta[c]);
  farMoved.anchor = city.anchor;
  objects[1].mesh = &farMoved;
  const auto pair = cullFor(objects, {closeUp()});
  EXPECT_EQ(pair->subsets[1].triangleCount(), 0u);
  test::expectIdentical(test::render(*pair->culled, closeUp()),
                        test::render(*pair->full, closeUp()), "empty");
}

TEST(CullingShared, BunnyCloseUpAndThinLensAreBitIdentical) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const Mesh bunny = loadMesh(path);
  CameraParams p;
  p.eye = glm::dvec3(-0.02, 0.13, 0.08);
  p.at = glm::dvec3(-0.03, 0.15, 0.0);
  p.width = 96;
  p.height = 96;
  p.fovDeg = 25;
  CameraParams lens = p;
  lens.type = "thinlens";
  lens.apertureRadius = 0.003;
  lens.focusDistance = 0.09;
  lens.spp = 4;
  for (const CameraParams& c : {p, lens}) {
    const auto pair = cullFor({{&bunny, glm::dmat4(1.0), nullptr}}, {c});
    EXPECT_LT(pair->stats.trianglesKept, bunny.triangleCount());
    test::expectIdentical(test::render(*pair->culled, c), test::render(*pair->full, c), c.type);
  }
}

TEST(CullingCli, RenderWithCullWritesTheSamePixelsAndJobFilesAcceptCull) {
  const std::string dir = test::scratchDir();
  const std::string common = test::apertureBinary() +
                             " render --mesh procedural:city --eye -3,1.5,4 --at -5.6,1,-2.5 "
                             "--fov 35 --size 64,48 --aov all --out ";
  std::string out;
  ASSERT_EQ(test::runCommand(common + dir + "/a.exr", &out), 0) << out;
  ASSERT_EQ(test::runCommand(common + dir + "/b.exr --cull", &out), 0) << out;
  EXPECT_NE(out.find("culled to the view volume of 1 camera: kept"), std::string::npos) << out;
  test::expectIdentical(readExr(dir + "/b.exr"), readExr(dir + "/a.exr"), "cli");

  test::writeFile(dir + "/job.json", R"({
    "scene": {"meshes": [{"path": "procedural:city"}], "placement": "world-space"},
    "cameras": [{"name": "a", "eye": [-3, 1.5, 4], "at": [-5.6, 1, -2.5], "fov": 35},
                {"name": "b", "eye": [9, 2, 3], "at": [0, 1, 0], "fov": 20}],
    "size": [48, 32], "aovs": "all", "output": ")" +
                                         dir + R"(/out/{camera}.exr",
    "performance": {"cull": true}})");
  ASSERT_EQ(test::runCommand(test::apertureBinary() + " batch " + dir + "/job.json", &out), 0)
      << out;
  EXPECT_NE(out.find("culled to the view volumes of 2 cameras"), std::string::npos) << out;
  ExrMetadata meta;
  readExr(dir + "/out/a.exr", &meta);
  bool worldSpace = false;
  for (const auto& [k, v] : meta.strings)
    worldSpace |= k == "aperture.placement" && v == "world-space";
  EXPECT_TRUE(worldSpace);
  test::writeFile(dir + "/bad.json", R"({"scene": {"meshes": [{"path": "procedural:city"}],
    "placement": "nowhere"}, "cameras": [{"name": "a", "eye": [1, 2, 3], "at": [0, 0, 0]}],
    "output": "x.exr"})");
  EXPECT_NE(test::runCommand(test::apertureBinary() + " batch " + dir + "/bad.json", &out), 0);
  EXPECT_NE(out.find("scene.placement"), std::string::npos) << out;
}

}  // namespace
}  // namespace aperture
