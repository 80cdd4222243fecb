// Frame-loop tests: closed-form values on analytic scenes, and bit-identical output for every
// packet width, tile size and thread count.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>

#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// A mesh from world-space triangles, anchored at `anchor` (no loader involved).
Mesh meshFrom(const std::vector<glm::dvec3>& verts, const std::vector<uint32_t>& idx,
              const glm::dvec3& anchor = glm::dvec3(0.0)) {
  Mesh m;
  m.name = "test";
  m.anchor = anchor;
  m.vertexCount = verts.size();
  for (const auto& v : verts)
    for (int c = 0; c < 3; ++c) m.positions.push_back(float(v[c] - anchor[c]));
  m.positions.resize(m.positions.size() + kVertexPaddingFloats, 0.0f);
  m.indices.assign(idx.begin(), idx.end());
  return m;
}

/// Square of side 2s in the plane z = z0, facing +z (counter-clockwise seen from +z).
Mesh quadMesh(double s, double z0) {
  return meshFrom({{-s, -s, z0}, {s, -s, z0}, {s, s, z0}, {-s, s, z0}}, {0, 1, 2, 0, 2, 3});
}

/// UV sphere of radius r at c: `seg` longitudes, `rings` latitudes.
Mesh sphereMesh(double r, const glm::dvec3& c, int seg, int rings) {
  std::vector<glm::dvec3> v;
  std::vector<uint32_t> idx;
  const double pi = 3.14159265358979323846;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j <= seg; ++j) {
      const double th = pi * i / rings, ph = 2 * pi * j / seg;
      v.push_back(c + r * glm::dvec3(std::sin(th) * std::cos(ph), std::cos(th),
                                     std::sin(th) * std::sin(ph)));
    }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < seg; ++j) {
      const uint32_t a = uint32_t(i * (seg + 1) + j), b = a + 1, cc = a + uint32_t(seg + 1),
                     d = cc + 1;
      idx.insert(idx.end(), {a, cc, b, b, cc, d});
    }
  return meshFrom(v, idx);
}

CameraParams lookAt(glm::dvec3 eye, glm::dvec3 at, int w, int h, double fov) {
  CameraParams p;
  p.eye = eye;
  p.at = at;
  p.width = w;
  p.height = h;
  p.fovDeg = fov;
  return p;
}

Framebuffer render(const Scene& scene, const CameraParams& p, AovMask aovs, int packet = 16,
                   int tile = 32) {
  auto cam = makeCamera(p, scene.renderOrigin());
  Framebuffer fb(p.width, p.height, aovs);
  RenderSettings rs;
  rs.packetWidth = packet;
  rs.tileSize = tile;
  rs.spp = p.spp;
  renderImage(scene, *cam, rs, fb);
  return fb;
}

}  // namespace

TEST(RenderAnalytic, PlaneFacingCameraMatchesClosedForm) {
  Device device;
  const double z0 = -7.0, s = 10.0;
  Mesh quad = quadMesh(s, z0);
  Scene scene(device, {&quad});
  // Eye at (0.3, -0.2, 2.5) looking down −z: planar depth is 2.5 − z0 everywhere.
  const glm::dvec3 eye(0.3, -0.2, 2.5);
  CameraParams p = lookAt(eye, eye + glm::dvec3(0, 0, -1), 33, 21, 60.0);
  Framebuffer fb = render(scene, p, parseAovList("all"));
  const double depth = eye.z - z0;
  const double vh = 2 * std::tan(30.0 * 3.14159265358979323846 / 180), vw = vh * 33 / 21;
  for (int i : {0, 5, 10, 20})
    for (int j : {0, 16, 32}) {
      const size_t px = size_t(i) * 33 + size_t(j);
      const double u = ((j + 0.5) / 33 - 0.5) * vw, v = -((i + 0.5) / 21 - 0.5) * vh;
      // The ray e + t·(u, v, −1)/|.| meets z = z0 at distance depth·|(u, v, −1)|.
      const glm::dvec3 hit = eye + depth * glm::dvec3(u, v, -1);
      const double dist = depth * std::sqrt(u * u + v * v + 1);
      EXPECT_NEAR(fb.depth[px], depth, 1e-5 * depth) << i << "," << j;
      EXPECT_NEAR(fb.distance[px], dist, 1e-5 * dist);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(fb.position[3 * px + c], hit[c], 1e-5 * dist) << "P component " << c;
      EXPECT_FLOAT_EQ(fb.normal[3 * px + 2], 1.0f);  // counter-clockwise from +z: normal +z
      EXPECT_EQ(fb.geomId[px], 0u);
      EXPECT_LT(fb.primId[px], 2u);
      const float shade = float(1 / std::sqrt(u * u + v * v + 1));  // |N·D|
      EXPECT_NEAR(fb.rgba[4 * px], shade, 1e-6);
      EXPECT_EQ(fb.rgba[4 * px + 3], 1.0f);
    }
}

TEST(RenderAnalytic, MissesAreInfiniteAndInvalid) {
  Device device;
  Mesh quad = quadMesh(0.5, -5.0);
  Scene scene(device, {&quad});
  Framebuffer fb = render(scene, lookAt({0, 0, 0}, {0, 0, -1}, 41, 41, 90.0), parseAovList("all"));
  const size_t corner = 0, centre = 20 * 41 + 20;
  EXPECT_TRUE(std::isinf(fb.depth[corner]) && fb.depth[corner] > 0);
  EXPECT_TRUE(std::isinf(fb.distance[corner]));
  EXPECT_EQ(fb.rgba[4 * corner + 3], 0.0f);
  EXPECT_EQ(fb.primId[corner], kInvalidId);
  EXPECT_EQ(fb.geomId[corner], kInvalidId);
  EXPECT_NEAR(fb.depth[centre], 5.0, 5e-6);
}

TEST(RenderAnalytic, TessellatedSphereWithinChordBound) {
  Device device;
  const double r = 2.0;
  const glm::dvec3 c(0.5, -0.25, -10.0);
  const int seg = 256, rings = 128;
  Mesh sphere = sphereMesh(r, c, seg, rings);
  Scene scene(device, {&sphere});
  const glm::dvec3 eye(0, 0, 0);
  CameraParams p = lookAt(eye, c, 64, 64, 20.0);
  Framebuffer fb = render(scene, p, parseAovList("depth,distance,normal,position"));
  auto cam = makeCamera(p);
  const CameraDescription desc = cam->describe();
  // A flat facet lies at most the sagitta r(1 − cos(π/rings)) inside the sphere (the longer
  // angular step bounds both directions), so hits are that close to the true surface.
  const double pi = 3.14159265358979323846;
  const double sag = r * (1 - std::cos(pi / rings));
  int checked = 0;
  for (int i = 0; i < 64; i += 3)
    for (int j = 0; j < 64; j += 3) {
      const size_t px = size_t(i) * 64 + size_t(j);
      double u = ((j + 0.5) / 64 - 0.5) * desc.vw, v = -((i + 0.5) / 64 - 0.5) * desc.vh;
      const glm::dvec3 d = glm::normalize(u * desc.u + v * desc.v - desc.d * desc.w);
      // Closed-form ray-sphere distance.
      const glm::dvec3 oc = eye - c;
      const double b = glm::dot(oc, d), disc = b * b - (glm::dot(oc, oc) - r * r);
      if (disc < 0.05 * r * r) continue;  // grazing rays: the facet bound is not tight there
      const double t = -b - std::sqrt(disc);
      const glm::dvec3 hit = eye + t * d;
      const double cosine = std::fabs(glm::dot(d, glm::normalize(hit - c)));
      ++checked;
      EXPECT_NEAR(fb.distance[px], t, sag / cosine + 1e-5 * t) << i << "," << j;
      EXPECT_NEAR(fb.depth[px], t * glm::dot(d, -desc.w), sag / cosine + 1e-5 * t);
      const glm::dvec3 n(fb.normal[3 * px], fb.normal[3 * px + 1], fb.normal[3 * px + 2]);
      EXPECT_GT(std::fabs(glm::dot(n, glm::normalize(hit - c))), std::cos(2 * pi / rings * 1.5));
      const glm::dvec3 pos(fb.position[3 * px], fb.position[3 * px + 1], fb.position[3 * px + 2]);
      EXPECT_NEAR(glm::length(pos - c), r, sag + 1e-5 * r);
    }
  EXPECT_GT(checked, 100);
}

TEST(RenderDeterminism, PacketWidthsTilesAndThreadsAreBitIdentical) {
  Device device;
  Mesh sphere = sphereMesh(1.0, {0, 0, 0}, 96, 48);
  Scene scene(device, {&sphere});
  CameraParams p = lookAt({0.3, 0.4, 3.0}, {0, 0, 0}, 77, 53, 45.0);  // odd sizes: tail lanes
  const AovMask all = parseAovList("all");
  const Framebuffer ref = render(scene, p, all, 1, 4);
  for (int packet : {1, 4, 8, 16})
    for (int tile : {4, 16, 64})
      for (int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        EXPECT_EQ(test::differingAovs(render(scene, p, all, packet, tile), ref), "")
            << "packet " << packet << " tile " << tile << " threads " << threads;
      }
}

TEST(RenderSettingsCheck, RejectsBadValues) {
  RenderSettings s;
  s.packetWidth = 3;
  EXPECT_THROW(validateRenderSettings(s), Error);
  s.packetWidth = 16;
  s.tileSize = 30;
  EXPECT_THROW(validateRenderSettings(s), Error);
  s.tileSize = 32;
  EXPECT_NO_THROW(validateRenderSettings(s));
  // spp has one check, the camera schema's (cameras/schema/param_schema.h), run by makeCamera.
  CameraParams p;
  p.spp = 0;
  EXPECT_THROW(makeCamera(p), Error);
}

TEST(RenderAovs, OnlyRequestedBuffersAreWritten) {
  Device device;
  Mesh quad = quadMesh(5, -3);
  Scene scene(device, {&quad});
  Framebuffer fb = render(scene, lookAt({0, 0, 0}, {0, 0, -1}, 16, 16, 40), kAovDepth);
  EXPECT_TRUE(fb.rgba.empty() && fb.normal.empty() && fb.primId.empty());
  EXPECT_NEAR(fb.depth[0], 3.0, 3e-6);
}

TEST(RenderInstances, RepeatedMeshMatchesCopiesAndReportsObjectIds) {
  Device device;
  Mesh sphere = sphereMesh(1.0, {0, 0, 0}, 64, 32);
  // Two placements of one mesh: translated left, and rotated 90° about y + translated right.
  glm::dmat4 left = glm::dmat4(1.0), right = glm::dmat4(1.0);
  left[3] = glm::dvec4(-1.5, 0, 0, 1);
  right[0] = glm::dvec4(0, 0, -1, 0);
  right[2] = glm::dvec4(1, 0, 0, 0);
  right[3] = glm::dvec4(1.5, 0, 0, 1);
  Scene instanced(device, std::vector<SceneObject>{{&sphere, left}, {&sphere, right}});
  EXPECT_EQ(instanced.instanceCount(), 2u);
  EXPECT_EQ(instanced.stats().uniqueTriangles, sphere.triangleCount());
  EXPECT_EQ(instanced.stats().triangles, 2 * sphere.triangleCount());
  // The same two spheres with the transforms baked into copies (an independent path).
  auto baked = [&](const glm::dmat4& m) {
    std::vector<glm::dvec3> v;
    for (size_t k = 0; k < sphere.vertexCount; ++k)
      v.push_back(glm::dvec3(m * glm::dvec4(glm::dvec3(sphere.vertex(k)), 1.0)));
    return meshFrom(v, {sphere.indices.begin(), sphere.indices.end()}, glm::dvec3(0.0));
  };
  Mesh a = baked(left), b = baked(right);
  // Both copies are anchored at the origin, used once and untransformed: attached directly.
  Scene copies(device, std::vector<SceneObject>{{&a, glm::dmat4(1.0)}, {&b, glm::dmat4(1.0)}});
  EXPECT_EQ(copies.instanceCount(), 0u);
  CameraParams p = lookAt({0.2, 1.0, 5.0}, {0, 0, 0}, 64, 40, 50.0);
  const AovMask aovs = parseAovList("depth,normal,primid,geomid");
  test::expectSameGeometry(render(instanced, p, aovs), render(copies, p, aovs), 301);
}

TEST(RenderSamples, WithoutColorOnlyTheCentreRayIsTracedAndGeometryIsUnchanged) {
  Device device;
  Mesh sphere = sphereMesh(1.0, {0, 0, 0}, 48, 24);
  Scene scene(device, {&sphere});
  CameraParams p = lookAt({0.3, 0.4, 3.0}, {0, 0, 0}, 40, 30, 45.0);
  p.spp = 16;
  auto cam = makeCamera(p, scene.renderOrigin());
  RenderSettings rs;
  rs.spp = 16;
  Framebuffer depthOnly(40, 30, kAovDepth), withColor(40, 30, kAovDepth | kAovColor);
  const RenderStats a = renderImage(scene, *cam, rs, depthOnly);
  const RenderStats b = renderImage(scene, *cam, rs, withColor);
  EXPECT_EQ(a.raysTraced, 40u * 30u);            // one ray a pixel: the centre ray
  EXPECT_EQ(b.raysTraced, 17u * 40u * 30u);      // color averages 16, plus the centre ray
  EXPECT_EQ(a.raysSkipped + b.raysSkipped, 0u);  // the sphere's view has no masked lanes
  EXPECT_EQ(test::differingAovs(depthOnly,
                                [&] {
                                  Framebuffer d(40, 30, kAovDepth);
                                  d.depth = withColor.depth;
                                  return d;
                                }()),
            "");
}
