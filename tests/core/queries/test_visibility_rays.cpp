// Face visibility's rays (core/queries/visibility.h, FaceRays): the default traces only the rays
// that can change the answer, and every array equals the reference that traces one ray per
// projected face, bit for bit: perspective, calibrated distorted (OPENCV, OPENCV_FISHEYE) and
// grazing cameras, faces far smaller than a pixel, occluders, both sides, and the shared bunny
// and dragon when present. The rays traced are counted through the packet observer, so the
// comparison cannot pass by running the reference twice.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "core/engine/packet.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/queries/visibility.h"
#include "tests/numerics_support.h"
#include "tests/support.h"
#include "tests/visibility_support.h"

namespace aperture {
namespace visibility_rays_test {

using namespace test::visibility;

namespace {

std::atomic<uint64_t> tracedLanes{0};

void countLanes(int width, const int* valid, const RayLanes&) {
  uint64_t n = 0;
  for (int k = 0; k < width; ++k) n += valid[k] != 0;
  tracedLanes += n;
}

/// faceVisibility with `rays`, and the lanes it traced (the primID renders included).
FaceVisibility traced(const Scene& scene, const Cameras& cams, bool frontOnly, FaceRays rays,
                      uint64_t& lanes) {
  FaceVisibilityOptions o;
  o.frontOnly = frontOnly;
  o.rays = rays;
  tracedLanes = 0;
  packetObserver = &countLanes;
  FaceVisibility v = faceVisibility(scene, cams.list, o);
  packetObserver = nullptr;
  lanes = tracedLanes;
  return v;
}

void expectSameRows(const SparseRows& a, const SparseRows& b, const char* what) {
  EXPECT_EQ(a.indptr, b.indptr) << what;
  EXPECT_EQ(a.indices, b.indices) << what;
}

/// Both methods, both sides: every array equal; with frontOnly the default traces fewer rays
/// than the reference whenever some face is met from behind (`backFaces`), and the same number
/// without it.
void expectNeededEqualsAll(const Scene& scene, const Cameras& cams, bool backFaces = true) {
  for (bool frontOnly : {false, true}) {
    SCOPED_TRACE(frontOnly ? "front only" : "both sides");
    uint64_t allLanes = 0, neededLanes = 0;
    const FaceVisibility all = traced(scene, cams, frontOnly, FaceRays::all, allLanes);
    const FaceVisibility needed = traced(scene, cams, frontOnly, FaceRays::needed, neededLanes);
    EXPECT_EQ(needed.viewCount, all.viewCount);
    EXPECT_EQ(needed.pixels, all.pixels);
    EXPECT_EQ(needed.bestView, all.bestView);
    expectSameRows(needed.cameraFaces, all.cameraFaces, "camera faces");
    expectSameRows(needed.faceCameras, all.faceCameras, "face cameras");
    uint64_t seen = 0;
    for (uint32_t n : all.viewCount) seen += n;
    EXPECT_GT(seen, 0u) << "the scene must show something";
    if (frontOnly && backFaces)
      EXPECT_LT(neededLanes, allLanes);
    else
      EXPECT_EQ(neededLanes, allLanes);
  }
}

CameraParams calibrated(const char* model, glm::dvec3 eye, glm::dvec3 at, int w, int h,
                        std::vector<double> k, std::vector<double> distortion) {
  CameraParams p;
  p.type = "calibrated";
  p.eye = eye, p.at = at, p.up = glm::dvec3(0, 1, 0.1);
  p.width = w, p.height = h;
  p.lensModel = model;
  p.intrinsics = k;
  p.distortion = distortion;
  return p;
}

/// A wavy sheet of n x n quads over [−1, 1]² in the plane y = 0 (bumps of 0.03), each quad's
/// diagonal alternating, plus a closed sphere of radius 0.25 above it at (0.2, 0.3, 0) of
/// 2·s·s triangles: at 64 x 48 pixels every face is smaller than a pixel, the sphere hides
/// the sheet under it and its own far side, and the sheet's bumps hide each other at grazing
/// angles.
Mesh sheetAndSphere(int n, int s) {
  MeshBuilder b;
  auto sheet = [&](int i, int j) {
    const double x = -1 + 2.0 * i / n, z = -1 + 2.0 * j / n;
    return glm::dvec3(x, 0.03 * std::sin(9 * x) * std::cos(7 * z), z);
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const glm::dvec3 a = sheet(i, j), c = sheet(i + 1, j + 1);
      if ((i + j) % 2)
        b.quad(a, sheet(i, j + 1), c, sheet(i + 1, j));
      else
        b.quad(sheet(i + 1, j), a, sheet(i, j + 1), c);
    }
  const double pi = 3.14159265358979323846;
  auto sphere = [&](int i, int j) {
    const double th = pi * i / s, ph = 2 * pi * j / s;
    return glm::dvec3(0.2, 0.3, 0.0) + 0.25 * glm::dvec3(std::sin(th) * std::cos(ph), std::cos(th),
                                                         std::sin(th) * std::sin(ph));
  };
  for (int i = 0; i < s; ++i)
    for (int j = 0; j < s; ++j)
      b.quad(sphere(i, j), sphere(i, j + 1), sphere(i + 1, j + 1), sphere(i + 1, j));
  return b.mesh(glm::dvec3(0.1, 0.0, -0.2));
}

std::vector<CameraParams> sheetCameras() {
  return {
      perspective({0.3, 1.2, 2.0}, {0, 0.1, 0}, {0, 1, 0}, 64, 48, 50),
      // Grazing: 2 cm above the sheet's bumps, looking along it.
      perspective({-1.6, 0.05, 0.1}, {1.0, 0.0, 0.0}, {0, 1, 0}, 64, 48, 60),
      perspective({0.2, 0.031, -1.8}, {0.2, 0.0, 1.0}, {0, 1, 0}, 64, 48, 40),
      // Calibrated and distorted: an OPENCV lens off-centre, a wide OPENCV_FISHEYE.
      calibrated("OPENCV", {1.1, 0.9, 1.4}, {0, 0.1, 0}, 64, 48, {58, 52, 35, 21},
                 {-0.2, 0.05, 1e-3, -5e-4}),
      calibrated("OPENCV_FISHEYE", {-0.8, 0.15, -1.3}, {0.2, 0.1, 0.2}, 64, 48, {20, 20, 32, 24},
                 {0.05, -0.01, 0.002, -0.001}),
      calibrated("OPENCV", {0.0, 0.04, 1.9}, {0.0, 0.0, -1.0}, 64, 48, {70, 70, 31.5, 23.5},
                 {0.1, -0.05, 0.0, 0.0}),
  };
}

}  // namespace

TEST(VisibilityRays, NeededEqualsAllOnAWavySheetAndASphereSmallerThanPixels) {
  const Loaded built = sceneOf(sheetAndSphere(150, 60));
  const Cameras cams(*built.scene, sheetCameras());
  expectNeededEqualsAll(*built.scene, cams);
}

TEST(VisibilityRays, NeededEqualsAllOnTheSharedBunnyAndDragon) {
  APERTURE_REQUIRE_SHARED_MESH(bunnyPath, "stanford/bun_zipper.ply");
  {
    const test::Loaded bunny = test::load(bunnyPath);
    const glm::dvec3 at(-0.017, 0.11, 0.0);
    const Cameras cams(*bunny.scene, {perspective({-0.04, 0.14, 0.2}, at, {0.1, 1, 0}, 80, 60, 25),
                                      perspective({0.25, 0.115, -0.02}, at, {0, 1, 0}, 80, 60, 30),
                                      calibrated("OPENCV", {-0.1, 0.2, -0.22}, at, 80, 60,
                                                 {95, 90, 43, 27}, {-0.25, 0.07, 1e-3, -5e-4}),
                                      calibrated("OPENCV_FISHEYE", {0.12, 0.02, 0.16}, at, 80, 60,
                                                 {30, 30, 40, 30}, {0.05, -0.01, 0.002, -0.001})});
    expectNeededEqualsAll(*bunny.scene, cams);
  }
  const std::string dragonPath = test::sharedMesh("stanford/dragon_vrip.ply");
  if (dragonPath.empty()) GTEST_SKIP() << "../shared/meshes/stanford/dragon_vrip.ply is absent";
  const test::Loaded dragon = test::load(dragonPath);
  const glm::dvec3 at(0, 0.12, 0);
  const Cameras cams(*dragon.scene, {perspective({0.1, 0.2, 0.43}, at, {0, 1, 0}, 64, 48, 30),
                                     calibrated("OPENCV", {-0.44, 0.05, -0.1}, at, 64, 48,
                                                {120, 115, 33, 23}, {-0.2, 0.05, 1e-3, -5e-4})});
  expectNeededEqualsAll(*dragon.scene, cams);
}

}  // namespace visibility_rays_test
}  // namespace aperture
