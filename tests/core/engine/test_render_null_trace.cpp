// The null trace (RenderSettings::nullTrace, `aperture bench --null`): the frame loop without
// Embree. Every pixel must hold exactly the fake hit's values, computed here independently of
// the camera and the frame loop, and the stats must count every ray.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// A strip of `triangles` triangles in the plane z = z0 (no loader involved).
Mesh stripMesh(int triangles, double z0) {
  Mesh m;
  m.name = "strip";
  m.vertexCount = size_t(triangles) + 2;
  for (size_t k = 0; k < m.vertexCount; ++k)
    for (double c : {double(k), double(k % 2), z0}) m.positions.push_back(float(c));
  m.positions.resize(m.positions.size() + kVertexPaddingFloats, 0.0f);
  for (int t = 0; t < triangles; ++t)
    m.indices.insert(m.indices.end(), {uint32_t(t), uint32_t(t + 1), uint32_t(t + 2)});
  return m;
}

constexpr int kWidth = 37, kHeight = 23;  // not multiples of 4: the tail blocks run too
constexpr double kFovDeg = 50.0;          // vertical
const glm::dvec3 kEye(0.5, -1.25, 3.0);   // looking down −z, up +y: U = +x, V = +y, W = +z

CameraParams perspectiveParams(int spp = 1) {
  CameraParams p;
  p.eye = kEye;
  p.at = kEye + glm::dvec3(0, 0, -1);
  p.width = kWidth;
  p.height = kHeight;
  p.fovDeg = kFovDeg;
  p.spp = spp;
  return p;
}

RenderSettings nullSettings(int packetWidth, int spp = 1) {
  RenderSettings rs;
  rs.packetWidth = packetWidth;
  rs.tileSize = 8;
  rs.spp = spp;
  rs.nullTrace = true;
  return rs;
}

/// The unit world direction of the centre ray of pixel (i, j), written from the pinhole
/// model: image plane at distance 1, centre of pixel (i, j) at raster (j + ½, i + ½).
glm::dvec3 centreDirection(int i, int j) {
  const double vh = 2 * std::tan(kFovDeg / 2 * 3.14159265358979323846 / 180);
  const double vw = vh * kWidth / kHeight;
  const double u = ((j + 0.5) / kWidth - 0.5) * vw, v = (0.5 - (i + 0.5) / kHeight) * vh;
  return glm::normalize(glm::dvec3(u, v, -1.0));
}

/// The lane of pixel (i, j) in the frame loop's blocks of packet width n (4x4, 4x2, 2x2, 1x1
/// blocks aligned to the image's origin; lanes along the block's rows).
uint32_t laneOf(int i, int j, int n) {
  const int bw = n == 1 ? 1 : n == 4 ? 2 : 4, bh = n / bw;
  return uint32_t((i % bh) * bw + j % bw);
}

/// The scene all tests share: a strip of `triangles` behind the camera (z = 10 > eye), so a
/// real trace hits nothing and every value below can only come from the fake hits.
struct StripScene {
  Device device;
  Mesh strip;
  Scene scene;
  explicit StripScene(int triangles) : strip(stripMesh(triangles, 10.0)), scene(device, {&strip}) {}
};

}  // namespace

TEST(NullTrace, EveryPixelHoldsTheFakeHit) {
  StripScene s(40);
  auto cam = makeCamera(perspectiveParams(), s.scene.renderOrigin());
  for (int n : {1, 4, 8, 16}) {
    Framebuffer fb(kWidth, kHeight, parseAovList("all") | kAovShadingNormal);
    const RenderStats st = renderImage(s.scene, *cam, nullSettings(n), fb);
    EXPECT_EQ(st.raysTraced, uint64_t(kWidth * kHeight)) << "packet " << n;
    EXPECT_EQ(st.hits, uint64_t(kWidth * kHeight)) << "packet " << n;
    EXPECT_EQ(st.raysSkipped, 0u);
    int bad = 0;
    for (int i = 0; i < kHeight; ++i)
      for (int j = 0; j < kWidth; ++j) {
        const size_t px = size_t(i) * kWidth + size_t(j);
        const glm::dvec3 d = centreDirection(i, j);
        // t = 1 along a unit direction from the eye: planar depth is d·(−W) = −d.z.
        const bool ok = std::fabs(fb.depth[px] - -d.z) < 1e-6 && fb.distance[px] == 1.0f &&
                        std::fabs(fb.normal[3 * px] - -d.x) < 1e-6 &&
                        std::fabs(fb.normal[3 * px + 1] - -d.y) < 1e-6 &&
                        std::fabs(fb.normal[3 * px + 2] - -d.z) < 1e-6 &&
                        // No vertex normals: the shading normal is the geometric one.
                        std::fabs(fb.shadingNormal[3 * px] - -d.x) < 1e-6 &&
                        std::fabs(fb.position[3 * px] - (kEye.x + d.x)) < 1e-5 &&
                        std::fabs(fb.position[3 * px + 1] - (kEye.y + d.y)) < 1e-5 &&
                        std::fabs(fb.position[3 * px + 2] - (kEye.z + d.z)) < 1e-5 &&
                        fb.primId[px] == laneOf(i, j, n) && fb.geomId[px] == 0u &&
                        // Eye-light shade |N·D| = 1 with N = −D; full coverage.
                        std::fabs(fb.rgba[4 * px] - 1.0f) < 1e-6 && fb.rgba[4 * px + 3] == 1.0f;
        if (!ok && ++bad <= 3)
          ADD_FAILURE() << "packet " << n << " pixel (" << i << ", " << j << "): depth "
                        << fb.depth[px] << " (want " << -d.z << "), distance " << fb.distance[px]
                        << ", normal " << fb.normal[3 * px] << "," << fb.normal[3 * px + 1] << ","
                        << fb.normal[3 * px + 2] << ", primID " << fb.primId[px] << " (want "
                        << laneOf(i, j, n) << "), geomID " << fb.geomId[px] << ", colour "
                        << fb.rgba[4 * px];
      }
    EXPECT_EQ(bad, 0) << "packet " << n;
  }
}

TEST(NullTrace, DepthCatchesTheHalfPixelShift) {
  // The test's closed form must tell the pixel-centre convention apart: the corner pixel's
  // depth with the centre at (j, i) instead of (j + ½, i + ½) differs by more than the
  // tolerance used above.
  StripScene s(40);
  auto cam = makeCamera(perspectiveParams(), s.scene.renderOrigin());
  Framebuffer fb(kWidth, kHeight, kAovDepth);
  renderImage(s.scene, *cam, nullSettings(16), fb);
  const double vh = 2 * std::tan(kFovDeg / 2 * 3.14159265358979323846 / 180);
  const double vw = vh * kWidth / kHeight;
  const glm::dvec3 shifted =
      glm::normalize(glm::dvec3((0.0 / kWidth - 0.5) * vw, (0.5 - 0.0 / kHeight) * vh, -1.0));
  EXPECT_NEAR(fb.depth[0], -centreDirection(0, 0).z, 1e-6);
  EXPECT_GT(std::fabs(fb.depth[0] - -shifted.z), 1e-4);
}

TEST(NullTrace, PrimIdWrapsAtTheTriangleCount) {
  // Object 0 has 3 triangles: lane k's fake primID is k mod 3, always a real triangle.
  StripScene s(3);
  auto cam = makeCamera(perspectiveParams(), s.scene.renderOrigin());
  Framebuffer fb(kWidth, kHeight, kAovPrimId | kAovShadingNormal);
  renderImage(s.scene, *cam, nullSettings(16), fb);
  for (int i = 0; i < kHeight; ++i)
    for (int j = 0; j < kWidth; ++j)
      ASSERT_EQ(fb.primId[size_t(i) * kWidth + size_t(j)], laneOf(i, j, 16) % 3)
          << "pixel (" << i << ", " << j << ")";
}

TEST(NullTrace, StatsCountEveryRayOfEveryPass) {
  // spp 3 with colour and a geometry AOV: three colour samples and one centre ray per pixel.
  StripScene s(40);
  auto cam = makeCamera(perspectiveParams(3), s.scene.renderOrigin());
  Framebuffer fb(kWidth, kHeight, kAovColor | kAovDepth);
  const RenderStats st = renderImage(s.scene, *cam, nullSettings(16, 3), fb);
  EXPECT_EQ(st.raysTraced, uint64_t(4 * kWidth * kHeight));
  EXPECT_EQ(st.hits, st.raysTraced);
  for (size_t px = 0; px < size_t(kWidth * kHeight); ++px)
    ASSERT_NEAR(fb.rgba[4 * px], 1.0f, 1e-6) << px;
}

TEST(NullTrace, OffTracesTheScene) {
  // The same frame without the switch goes through Embree: the strip behind the camera is
  // missed everywhere, so the values of the tests above came from the null trace.
  StripScene s(40);
  auto cam = makeCamera(perspectiveParams(), s.scene.renderOrigin());
  Framebuffer fb(kWidth, kHeight, kAovDepth | kAovPrimId);
  RenderSettings rs = nullSettings(16);
  rs.nullTrace = false;
  const RenderStats st = renderImage(s.scene, *cam, rs, fb);
  EXPECT_EQ(st.raysTraced, uint64_t(kWidth * kHeight));
  EXPECT_EQ(st.hits, 0u);
  EXPECT_TRUE(std::isinf(fb.depth[0]));
  EXPECT_EQ(fb.primId[0], kInvalidId);
}

TEST(NullTrace, LayeredHitsAreRefused) {
  StripScene s(40);
  auto cam = makeCamera(perspectiveParams(), s.scene.renderOrigin());
  AovSet aovs(kAovDepth);
  aovs.layers = 2;
  Framebuffer fb(kWidth, kHeight, aovs);
  EXPECT_NE(
      test::errorOf([&] { renderImage(s.scene, *cam, nullSettings(16), fb); }).find("layered hits"),
      std::string::npos);
}
