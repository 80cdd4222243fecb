// Face visibility (core/queries/visibility.h): hand-counted scenes, the primID renders'
// bincount, an independent pinhole and ray per seen face, projected areas in closed form, and
// bad inputs. Points: test_visibility_points.cpp.
#include <embree3/rtcore.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/queries/visibility.h"
#include "core/util/error.h"
#include "tests/numerics_support.h"
#include "tests/support.h"
#include "tests/visibility_support.h"

namespace aperture {
namespace visibility_test {

using namespace test::visibility;

namespace {

double triangleArea2d(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  const glm::dvec2 p = b - a, q = c - a;
  return 0.5 * std::abs(p.x * q.y - p.y * q.x);
}

// ---------------------------------------------------------------------------------------------
// The cube with an occluding plate.
//
// Cube [-0.9, 0.9]^3, outward counter-clockwise winding, each side a quad split along the
// diagonal from its first to its third corner. Faces (triangles) in mesh order:
//   0, 1 +z side   (0: the half holding corner (+x, −y), 1: the half holding (−x, +y))
//   2, 3 −z side   4, 5 +x side   6, 7 −x side   8, 9 +y side   10, 11 −y side
//   12, 13 a plate in the plane z = 2.4, x in [−0.3, 0], y in [−0.2, 0.2], facing +z
//   14 a tiny triangle (edges 0.02) in the plane x = 0.95, around (y, z) = (0.4875, 0.24375)
//
// Six perspective cameras at distance 2.9 on the axes looking at the origin: 0 +z, 1 −z (up
// +y), 2 +x, 3 −x, 4 +y, 5 −y (up +z). Image plane d = 2 with viewport 3 x 2.5 and 6 x 5
// pixels (0.5 a pixel), so pixel centres lie on the plane at
//   u in {±0.25, ±0.75, ±1.25} (columns), v in {0, ±0.5, ±1} (rows),
// and at depth 2, where the cube's near side lies, plane and world coordinates along the side
// coincide (scale depth / d = 1). The near side covers |u|, |v| < 0.9: 4 columns x 3 rows =
// 12 pixel centres, none on an edge (|u|, |v| != 0.9) nor on a diagonal (|u| != |v|). The grid
// is symmetric under (u, v) -> (−u, −v), which swaps the two halves of a side: each half
// holds 6 centres. Rays past the near side's square miss the cube (it is the silhouette).
//
// Camera 0 (+z): U = +x, V = +y. The plate at depth 0.5 scales by d / 0.5 = 4 onto the plane:
// u in [−1.2, 0], v in [−0.8, 0.8]. It covers the centres u in {−0.25, −0.75}, v in {0, ±0.5}
// (6 pixels: u = −1.25 and v = ±1 lie outside it), i.e. the left half of the cube's +z side.
//   Plate halves, diagonal from (−1.2, −0.8) to (0, 0.8): v = −0.8 + (4/3)(u + 1.2), at
//   u = −0.75 v = −0.2, at u = −0.25 v = 0.4667. Face 12 (below it, holding (0, −0.8)) gets
//   (−0.75, −0.5), (−0.25, −0.5), (−0.25, 0): 3; face 13 the other 3.
//   Cube +z side, remaining centres u in {0.25, 0.75}, v in {0, ±0.5}, diagonal v = u: face 0
//   (v < u) gets (0.25, 0), (0.25, −0.5) and the three at u = 0.75: 5; face 1 gets (0.25, 0.5).
//   Face 0's centroid (0.3, −0.3) lies beside the plate: seen. Face 1's centroid (−0.3, 0.3)
//   projects onto the plate, whose triangle the centre ray hits first: not seen, although one
//   pixel shows face 1. The plate's centroids (−0.1, −0.067) and (−0.2, 0.067): seen.
// Cameras 1 to 5 see their own near side unobstructed: 6 pixels and one view for each half.
// The plate lies outside their images: its points have |z| / depth >= 2.4 / 3.2 = 0.75, above
// the vertical half-extent 1.25 / 2 = 0.625 of cameras 2 to 5, and camera 1 sees it through
// the cube (it subtends tan <= 0.06 at depth 5.3; the cube's −z side, tan < 0.45).
// The tiny triangle: camera 2 (U = +y, V = +z) puts it at depth 1.95, on the plane around
// (u, v) = (0.5, 0.25), within 0.011 of it: no pixel centre (the nearest are 0.25 away) hits it,
// yet its centroid projects inside the image and its centre ray hits it: seen, 0 pixels. From
// every other camera the ray to it crosses the cube's near side first (e.g. camera 0 reaches
// the plane z = 0.9 at (0.715, 0.367)).
// Best views: each face is seen by at most one camera.

Mesh cubeWithPlate() {
  const double s = 0.9;
  MeshBuilder b;
  b.quad({-s, -s, s}, {s, -s, s}, {s, s, s}, {-s, s, s});                      // +z
  b.quad({-s, -s, -s}, {-s, s, -s}, {s, s, -s}, {s, -s, -s});                  // −z
  b.quad({s, -s, -s}, {s, s, -s}, {s, s, s}, {s, -s, s});                      // +x
  b.quad({-s, -s, -s}, {-s, -s, s}, {-s, s, s}, {-s, s, -s});                  // −x
  b.quad({-s, s, -s}, {-s, s, s}, {s, s, s}, {s, s, -s});                      // +y
  b.quad({-s, -s, -s}, {s, -s, -s}, {s, -s, s}, {-s, -s, s});                  // −y
  b.quad({-0.3, -0.2, 2.4}, {0, -0.2, 2.4}, {0, 0.2, 2.4}, {-0.3, 0.2, 2.4});  // plate
  const double y0 = 0.4875, z0 = 0.24375, e = 0.01;
  b.triangle({0.95, y0 - e, z0 - e}, {0.95, y0 + e, z0 - e}, {0.95, y0, z0 + e});  // tiny
  return b.mesh();
}

std::vector<CameraParams> axisCameras() {
  const glm::dvec3 axes[6] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  std::vector<CameraParams> all;
  for (int k = 0; k < 6; ++k) {
    CameraParams p;
    p.eye = 2.9 * axes[k];
    p.at = glm::dvec3(0.0);
    p.up = k < 2 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1);
    p.d = 2.0;
    p.viewport = glm::dvec2(3.0, 2.5);
    p.width = 6, p.height = 5;
    all.push_back(p);
  }
  return all;
}

}  // namespace

TEST(Visibility, CubeWithPlateMatchesTheHandCount) {
  const Loaded cube = sceneOf(cubeWithPlate());
  const Cameras cams(*cube.scene, axisCameras());
  const FaceVisibility v = faceVisibility(*cube.scene, cams.list);

  const std::vector<uint32_t> viewCount = {1, 0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
  const std::vector<uint64_t> pixels = {5, 1, 6, 6, 6, 6, 6, 6, 6, 6, 6, 6, 3, 3, 0};
  const std::vector<int32_t> best = {0, -1, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 0, 0, 2};
  EXPECT_EQ(v.viewCount, viewCount);
  EXPECT_EQ(v.pixels, pixels);
  EXPECT_EQ(v.bestView, best);

  const std::vector<std::vector<uint32_t>> cameraFaces = {{0, 12, 13}, {2, 3}, {4, 5, 14},
                                                          {6, 7},      {8, 9}, {10, 11}};
  ASSERT_EQ(v.cameraFaces.rows(), 6u);
  for (size_t c = 0; c < 6; ++c) EXPECT_EQ(row(v.cameraFaces, c), cameraFaces[c]) << "camera " << c;
  ASSERT_EQ(v.faceCameras.rows(), 15u);
  for (size_t f = 0; f < 15; ++f) {
    const std::vector<uint32_t> expect =
        best[f] < 0 ? std::vector<uint32_t>{} : std::vector<uint32_t>{uint32_t(best[f])};
    EXPECT_EQ(row(v.faceCameras, f), expect) << "face " << f;
  }
}

// The tiny triangle's pixel count of 0 is the renders' own: an independent bincount of the
// six primID images agrees, and no pixel shows face 14.
TEST(Visibility, TinyFaceIsSeenWithoutAPixel) {
  const Loaded cube = sceneOf(cubeWithPlate());
  const Cameras cams(*cube.scene, axisCameras());
  const FaceVisibility v = faceVisibility(*cube.scene, cams.list);
  uint64_t tinyPixels = 0;
  for (const Camera* cam : cams.list) {
    Framebuffer fb(6, 5, AovSet(kAovPrimId));
    renderImage(*cube.scene, *cam, RenderSettings{}, fb);
    for (uint32_t prim : fb.primId) tinyPixels += prim == 14;
  }
  EXPECT_EQ(tinyPixels, 0u);
  EXPECT_EQ(v.pixels[14], 0u);
  EXPECT_EQ(v.viewCount[14], 1u);
  EXPECT_EQ(v.bestView[14], 2);
}

TEST(Visibility, FrontOnlyCountsTheWindingSide) {
  MeshBuilder b;
  b.triangle({-1, -1, 0}, {1, -1, 0}, {0, 1, 0});  // counter-clockwise seen from +z
  const Loaded tri = sceneOf(b.mesh());
  const Cameras cams(*tri.scene, {perspective({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 8, 8, 60),
                                  perspective({0, 0, -3}, {0, 0, 0}, {0, 1, 0}, 8, 8, 60)});
  const FaceVisibility both = faceVisibility(*tri.scene, cams.list);
  FaceVisibilityOptions front;
  front.frontOnly = true;
  const FaceVisibility one = faceVisibility(*tri.scene, cams.list, front);
  EXPECT_EQ(both.viewCount, std::vector<uint32_t>{2});
  EXPECT_EQ(row(both.faceCameras, 0), (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(one.viewCount, std::vector<uint32_t>{1});
  EXPECT_EQ(row(one.faceCameras, 0), std::vector<uint32_t>{0});
  EXPECT_EQ(row(one.cameraFaces, 1), std::vector<uint32_t>{});
  // Pixels are the renders' and do not depend on the side.
  EXPECT_EQ(one.pixels, both.pixels);
  EXPECT_GT(both.pixels[0], 0u);
}

// Camera 1 at half camera 0's distance images the triangle 4 times larger; camera 2 repeats
// camera 1 exactly: the tie goes to the lower index, 1.
TEST(Visibility, BestViewIsTheLargestProjectionTiesToTheLowerIndex) {
  MeshBuilder b;
  b.triangle({-0.5, -0.5, 0}, {0.5, -0.5, 0}, {0, 0.5, 0});
  const Loaded tri = sceneOf(b.mesh());
  const CameraParams far = perspective({0, 0, 6}, {0, 0, 0}, {0, 1, 0}, 32, 32, 40);
  const CameraParams near = perspective({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 32, 32, 40);
  const Cameras cams(*tri.scene, {far, near, near});
  const FaceVisibility v = faceVisibility(*tri.scene, cams.list);
  EXPECT_EQ(v.viewCount, std::vector<uint32_t>{3});
  EXPECT_EQ(v.bestView, std::vector<int32_t>{1});
  const Corners t = cornersOf(*tri.mesh, 0);
  EXPECT_NEAR(projectedAreaPixels(*cams.list[1], t.a, t.b, t.c),
              4 * projectedAreaPixels(*cams.list[0], t.a, t.b, t.c), 1e-9);
}

// face pixels are the bincount of the primID images renderImage makes, camera by camera (the
// visibility code renders through renderImages), on the bunny with a pinhole, a fisheye, a
// strongly distorted OPENCV lens and an OPENCV_FISHEYE lens, of different sizes.
TEST(Visibility, FacePixelsAreTheBincountOfPrimIdRenders) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const test::Loaded bunny = test::load(path);
  const glm::dvec3 eye(-0.02, 0.11, 0.35), at(-0.017, 0.11, 0);
  std::vector<CameraParams> params;
  params.push_back(perspective(eye, at, {0, 1, 0}, 96, 72, 30));
  CameraParams fish = perspective(eye, at, {0, 1, 0}, 80, 80, 30);
  fish.type = "fisheye";
  fish.fovDeg.reset();
  fish.fisheyeFovDeg = 40;
  params.push_back(fish);
  CameraParams opencv = perspective(eye, at, {0, 1, 0}, 90, 70, 30);
  opencv.fovDeg.reset();
  opencv.type = "calibrated";
  opencv.lensModel = "OPENCV";
  opencv.intrinsics = std::vector<double>{140, 135, 47, 33};
  opencv.distortion = std::vector<double>{-0.45, 0.1, 2e-3, -1e-3};
  params.push_back(opencv);
  CameraParams kb = opencv;
  kb.width = kb.height = 64;
  kb.lensModel = "OPENCV_FISHEYE";
  kb.intrinsics = std::vector<double>{90, 90, 32, 32};
  kb.distortion = std::vector<double>{0.1, -0.05, 0.01, 0.0};
  params.push_back(kb);
  const Cameras cams(*bunny.scene, params);

  const FaceVisibility v = faceVisibility(*bunny.scene, cams.list);
  std::vector<uint64_t> bincount(bunny.mesh->triangleCount(), 0);
  uint64_t hits = 0;
  for (size_t c = 0; c < params.size(); ++c) {
    const Framebuffer fb =
        test::render(*bunny.scene, params[c], kAovPrimId);  // renderImage, one camera
    for (uint32_t prim : fb.primId)
      if (prim != kInvalidId) ++bincount[prim], ++hits;
  }
  EXPECT_GT(hits, 4000u) << "the bunny must fill the views";
  EXPECT_EQ(v.pixels, bincount);
  for (size_t c = 0; c < params.size(); ++c)
    EXPECT_GT(v.cameraFaces.indptr[c + 1] - v.cameraFaces.indptr[c], 200u) << "camera " << c;
}

// Every face the visibility code says a pinhole sees, and every face it says it does not, is
// re-checked with the test's own pinhole (Pinhole above) and a single ray from the eye
// through the centroid (rtcIntersect1): seen = the centroid projects inside and that ray's
// first hit is the face.
TEST(Visibility, SeenFacesAgreeWithAnIndependentPinholeAndRay) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const test::Loaded bunny = test::load(path);
  const CameraParams p =
      perspective({-0.04, 0.14, 0.2}, {-0.017, 0.11, 0}, {0.1, 1, 0}, 120, 90, 25);
  const Cameras cams(*bunny.scene, {p});
  const FaceVisibility v = faceVisibility(*bunny.scene, cams.list);
  const Pinhole pin(p);
  const Mesh& mesh = *bunny.mesh;
  std::vector<char> listed(mesh.triangleCount(), 0);
  for (uint32_t f : row(v.cameraFaces, 0)) listed[f] = 1;

  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  const glm::dvec3 org = p.eye - bunny.scene->renderOrigin();
  size_t seen = 0, disagree = 0, outside = 0;
  for (size_t f = 0; f < mesh.triangleCount(); ++f) {
    const Corners t = cornersOf(mesh, f);
    const glm::dvec3 g = (t.a + t.b + t.c) / 3.0;
    const std::optional<glm::dvec2> r = pin.raster(g);
    bool ours = false;
    if (r && pin.inside(*r)) {
      const glm::dvec3 dir = glm::normalize(g - p.eye);
      RTCRayHit h{};
      h.ray.org_x = float(org.x), h.ray.org_y = float(org.y), h.ray.org_z = float(org.z);
      h.ray.dir_x = float(dir.x), h.ray.dir_y = float(dir.y), h.ray.dir_z = float(dir.z);
      h.ray.tnear = 0, h.ray.tfar = std::numeric_limits<float>::infinity();
      h.ray.mask = 0xFFFFFFFFu;
      h.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(bunny.scene->handle(), &ctx, &h);
      ours = h.hit.geomID == 0 && h.hit.primID == f;
    } else {
      ++outside;
    }
    seen += ours;
    disagree += ours != bool(listed[f]);
  }
  EXPECT_GT(seen, 3000u);
  EXPECT_GT(outside, 1000u) << "the view must cut the bunny so the inside test matters";
  EXPECT_EQ(disagree, 0u) << "of " << seen << " faces seen by the independent check";
  EXPECT_EQ(v.viewCount.size(), mesh.triangleCount());
}

// ---------------------------------------------------------------------------------------------
// projectedAreaPixels

// A camera at the origin looking down −z with a 60° vertical field on 200 x 100 pixels:
// f = 50 / tan 30° pixels. A triangle in the plane z = −4 images with area A·(f / 4)².
TEST(Visibility, ProjectedAreaOfAFrontoParallelTriangleIsTheClosedForm) {
  MeshBuilder b;
  b.triangle({0, 0, -1}, {1, 0, -1}, {0, 1, -1});
  const Loaded any = sceneOf(b.mesh());
  const CameraParams p = perspective({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 200, 100, 60);
  const auto cam = makeCamera(p, any.scene->renderOrigin());
  const double f = 50 / std::tan(30 * test::kDeg);
  for (const glm::dvec2 shift : {glm::dvec2(0, 0), glm::dvec2(1.0, -0.5)}) {
    const glm::dvec3 a(shift.x, shift.y, -4), bb = a + glm::dvec3(0.5, 0, 0),
                                              c = a + glm::dvec3(0, 0.3, 0);
    const double want = 0.5 * 0.5 * 0.3 * (f / 4) * (f / 4);
    EXPECT_NEAR(projectedAreaPixels(*cam, a, bb, c), want, 1e-9 * want);
  }
}

// Corner a lies behind the camera. Centroid g has z = −1; halving once puts a at z = 0.5
// (still behind), twice at z = −0.25 (in front): the area is 4² times the area of the twice
// halved triangle, projected by the test's own pinhole. A triangle whose centroid is behind
// the camera has area 0.
TEST(Visibility, ProjectedAreaShrinksATriangleCrossingBehindTheCamera) {
  MeshBuilder b;
  b.triangle({0, 0, -1}, {1, 0, -1}, {0, 1, -1});
  const Loaded any = sceneOf(b.mesh());
  const CameraParams p = perspective({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 200, 100, 60);
  const auto cam = makeCamera(p, any.scene->renderOrigin());
  const Pinhole pin(p);
  const glm::dvec3 a(0.1, 0, 2), bb(-0.3, -0.3, -2.5), c(0.3, -0.3, -2.5);
  const glm::dvec3 g = (a + bb + c) / 3.0;
  ASSERT_NEAR(g.z, -1, 1e-12);
  ASSERT_FALSE(pin.raster(g + 0.5 * (a - g)));
  auto quarter = [&](const glm::dvec3& x) { return *pin.raster(g + 0.25 * (x - g)); };
  const double want = 16 * triangleArea2d(quarter(a), quarter(bb), quarter(c));
  EXPECT_NEAR(projectedAreaPixels(*cam, a, bb, c), want, 1e-9 * want);
  EXPECT_EQ(projectedAreaPixels(*cam, a, a + glm::dvec3(1, 0, 0), a + glm::dvec3(0, 1, 0)), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Errors

TEST(Visibility, BadInputsAreErrorsNamingTheValue) {
  MeshBuilder b;
  b.quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0});
  const Mesh m1 = b.mesh(), m2 = b.mesh();
  const Scene two(test::numericsDevice(), std::vector<const Mesh*>{&m1, &m2});
  const Cameras cams(two, {perspective({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 16, 16, 40)});
  std::string e = test::errorOf([&] { faceVisibility(two, cams.list); });
  EXPECT_NE(e.find("2 objects"), std::string::npos) << e;
  e = test::errorOf([&] { pointVisibility(two, cams.list, {}); });
  EXPECT_NE(e.find("2 objects"), std::string::npos) << e;

  const Loaded one = sceneOf(b.mesh());
  PointVisibilityOptions o;
  o.tolerance = 1.0;
  e = test::errorOf([&] { pointVisibility(*one.scene, cams.list, {{0, 0, 1}}, o); });
  EXPECT_NE(e.find("tolerance 1 "), std::string::npos) << e;
  o.tolerance = -0.5;
  e = test::errorOf([&] { pointVisibility(*one.scene, cams.list, {{0, 0, 1}}, o); });
  EXPECT_NE(e.find("tolerance -0.5"), std::string::npos) << e;
  const std::vector<glm::dvec3> pts = {{0, 0, 1}, {0, 0, 2}, {0, 0, 3}, {0, std::nan(""), 0}};
  e = test::errorOf([&] { pointVisibility(*one.scene, cams.list, pts); });
  EXPECT_NE(e.find("point 3"), std::string::npos) << e;
  e = test::errorOf([&] { classifyObservations(*one.scene, cams.list, pts, {}, 1.5); });
  EXPECT_NE(e.find("tolerance 1.5"), std::string::npos) << e;
}

// No camera: nothing is seen, every face has an empty row; progress reports each camera once.
TEST(Visibility, EmptyCameraListAndProgress) {
  const Loaded cube = sceneOf(cubeWithPlate());
  const FaceVisibility none = faceVisibility(*cube.scene, {});
  EXPECT_EQ(none.viewCount, std::vector<uint32_t>(15, 0));
  EXPECT_EQ(none.bestView, std::vector<int32_t>(15, -1));
  EXPECT_EQ(none.cameraFaces.rows(), 0u);
  EXPECT_EQ(none.faceCameras.indptr, std::vector<uint64_t>(16, 0));

  const Cameras cams(*cube.scene, axisCameras());
  std::vector<size_t> calls;
  FaceVisibilityOptions o;
  o.progress = [&](size_t done, size_t total) {
    EXPECT_EQ(total, 6u);
    calls.push_back(done);
  };
  faceVisibility(*cube.scene, cams.list, o);
  EXPECT_EQ(calls, (std::vector<size_t>{1, 2, 3, 4, 5, 6}));
}

}  // namespace visibility_test
}  // namespace aperture
