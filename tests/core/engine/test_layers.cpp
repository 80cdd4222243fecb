// Layered hits (issue 12 item 5): the first K surfaces along each pixel-centre ray, checked
// against a brute-force intersection of the same ray with every triangle (Möller–Trumbore in
// double, written here), for both methods, every packet width, culled and instanced scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <memory>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/layers.h"
#include "core/engine/packet.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/numerics_support.h"

namespace aperture {
namespace {

/// Restores the process's layer method after a test that picks one.
struct MethodGuard {
  LayerMethod saved = defaultLayerMethod();
  ~MethodGuard() { setLayerMethod(saved); }
};

Mesh worldMesh(const std::string& spec) {
  LoadOptions lo;
  lo.placement = Placement::WorldSpace;
  return loadMesh(spec, lo);
}

BuildOptions withFilter() {
  BuildOptions bo;
  bo.contextFilter = true;
  return bo;
}

/// Looking down −z at spheres stacked along the view axis: every centre-ish ray crosses
/// several closed surfaces.
CameraParams stackCamera() {
  CameraParams p;
  p.eye = glm::dvec3(0.13, 0.07, 12.0);
  p.at = glm::dvec3(0.0, 0.0, 0.0);
  p.width = 37;
  p.height = 29;
  p.fovDeg = 22;
  return p;
}

struct BruteHit {
  double t;
  uint32_t primId, geomId;
};

/// What the brute force expects of one pixel, and whether the pixel's answer is ambiguous in
/// float (a ray within 1e-7 of a triangle edge in barycentrics, or two hits closer in t than
/// the tolerance): the fixtures are chosen so that no pixel is.
struct BruteRay {
  std::vector<BruteHit> hits;  // sorted by t
  bool ambiguous = false;
};

/// One placed triangle set for the brute force: vertices in render space, the primID each
/// triangle reports (the mesh's own index), the geomID (object).
struct BruteObject {
  std::vector<glm::dvec3> v;  // 3 per triangle
  std::vector<uint32_t> primIds;
  uint32_t geomId;
};

BruteObject bruteObject(const Mesh& m, const glm::dmat4& worldFromMesh, const glm::dvec3& origin,
                        uint32_t geomId, const TriangleSubset* subset = nullptr) {
  BruteObject o;
  o.geomId = geomId;
  const size_t n = subset ? subset->triangleCount() : m.triangleCount();
  const uint32_t* idx = subset ? subset->indices.data() : m.indices.data();
  for (size_t t = 0; t < n; ++t) {
    for (int c = 0; c < 3; ++c) {
      const glm::dvec3 local = m.anchor + glm::dvec3(m.vertex(idx[3 * t + size_t(c)]));
      o.v.push_back(glm::dvec3(worldFromMesh * glm::dvec4(local, 1.0)) - origin);
    }
    o.primIds.push_back(subset ? subset->primIds[t] : uint32_t(t));
  }
  return o;
}

/// The camera's centre ray of pixel (i, j), origin and direction in double.
struct CentreRay {
  glm::dvec3 org, dir;
};
CentreRay centreRayOf(const Camera& cam, int i, int j) {
  RTCRayHit ray;
  RayLanes lanes = rayLanes<1>(ray);
  int valid[1] = {-1};
  cam.generate({j, i, 1, 1, PacketRequest::kCentreRay}, lanes, valid);
  return {{ray.ray.org_x, ray.ray.org_y, ray.ray.org_z},
          {ray.ray.dir_x, ray.ray.dir_y, ray.ray.dir_z}};
}

BruteRay bruteForce(const std::vector<BruteObject>& objects, const glm::dvec3& org,
                    const glm::dvec3& dir) {
  BruteRay r;
  for (const BruteObject& o : objects)
    for (size_t t = 0; t < o.primIds.size(); ++t) {
      const glm::dvec3 a = o.v[3 * t], e1 = o.v[3 * t + 1] - a, e2 = o.v[3 * t + 2] - a;
      const glm::dvec3 p = glm::cross(dir, e2);
      const double det = glm::dot(e1, p);
      if (det == 0.0) continue;
      const glm::dvec3 s = org - a, q = glm::cross(s, e1);
      const double u = glm::dot(s, p) / det, v = glm::dot(dir, q) / det;
      const double dist = glm::dot(e2, q) / det;
      const double margin = std::min({u, v, 1.0 - u - v});
      if (dist <= 0.0) continue;
      if (std::fabs(margin) < 1e-7) r.ambiguous = true;
      if (margin >= 0.0) r.hits.push_back({dist, o.primIds[t], o.geomId});
    }
  std::sort(r.hits.begin(), r.hits.end(),
            [](const BruteHit& x, const BruteHit& y) { return x.t < y.t; });
  for (size_t k = 1; k < r.hits.size(); ++k)
    if (r.hits[k].t - r.hits[k - 1].t < 1e-4 * r.hits[k].t) r.ambiguous = true;
  return r;
}

Framebuffer renderLayers(const Scene& scene, const CameraParams& p, int layers, AovMask mask,
                         int packet, LayerMethod method) {
  setLayerMethod(method);
  const auto cam = makeCamera(p, scene.renderOrigin());
  AovSet set(mask);
  set.layers = layers;
  Framebuffer fb(p.width, p.height, set);
  RenderSettings rs;
  rs.packetWidth = packet;
  rs.spp = p.spp;
  renderImage(scene, *cam, rs, fb);
  return fb;
}

/// Compares every pixel's layers with the brute force; returns the number of hits checked.
int expectLayersMatchBruteForce(const Scene& scene, const std::vector<BruteObject>& objects,
                                const CameraParams& p, int layers, int packet, LayerMethod method) {
  const Framebuffer fb = renderLayers(scene, p, layers, kAovDepth, packet, method);
  const auto cam = makeCamera(p, scene.renderOrigin());
  const glm::dvec3 axis = glm::normalize(*p.at - p.eye);
  const glm::dvec3 eye = p.eye - scene.renderOrigin();  // render space
  const size_t n = fb.pixelCount();
  const float inf = std::numeric_limits<float>::infinity();
  int checked = 0, ambiguous = 0;
  for (int i = 0; i < p.height; ++i)
    for (int j = 0; j < p.width; ++j) {
      const auto [org, dir] = centreRayOf(*cam, i, j);
      const BruteRay want = bruteForce(objects, org, dir);
      ambiguous += want.ambiguous;
      const size_t px = size_t(i) * size_t(p.width) + size_t(j);
      for (int k = 0; k < layers; ++k) {
        const size_t at = size_t(k) * n + px;
        const std::string where = ::testing::PrintToString(std::vector<int>{i, j, k}) + " " +
                                  layerMethodName(method) + " packet " + std::to_string(packet);
        if (size_t(k) >= want.hits.size()) {
          EXPECT_EQ(fb.layerDistance[at], inf) << where;
          EXPECT_EQ(fb.layerDepth[at], inf) << where;
          EXPECT_EQ(fb.layerPrimId[at], kInvalidId) << where;
          EXPECT_EQ(fb.layerGeomId[at], kInvalidId) << where;
          continue;
        }
        const BruteHit& h = want.hits[size_t(k)];
        EXPECT_NEAR(fb.layerDistance[at], h.t, 2e-6 * h.t) << where;
        const double z = glm::dot(org - eye, axis) + h.t * glm::dot(dir, axis);
        EXPECT_NEAR(fb.layerDepth[at], z, 2e-6 * h.t) << where;
        EXPECT_EQ(fb.layerPrimId[at], h.primId) << where;
        EXPECT_EQ(fb.layerGeomId[at], h.geomId) << where;
        ++checked;
      }
    }
  EXPECT_EQ(ambiguous, 0) << "the fixture has rays the float answer may differ on";
  return checked;
}

/// Three spheres along the view axis (radii 1, 1.6, 1) and one beside them overlapping the
/// middle one's silhouette: up to 8 surfaces along a ray.
struct SphereStack {
  std::vector<Mesh> meshes;
  std::unique_ptr<Scene> scene;
  std::vector<BruteObject> brute;

  SphereStack() {
    for (const char* spec :
         {"procedural:sphere?radius=1&cz=3&segments=24&rings=12",
          "procedural:sphere?radius=1.6&segments=20&rings=10",
          "procedural:sphere?radius=1&cz=-3.5&segments=18&rings=9",
          "procedural:sphere?radius=0.7&cx=1.1&cy=0.4&cz=-1&segments=16&rings=8"})
      meshes.push_back(worldMesh(spec));
    std::vector<const Mesh*> ptrs;
    for (const Mesh& m : meshes) ptrs.push_back(&m);
    scene = std::make_unique<Scene>(test::numericsDevice(), ptrs, withFilter());
    for (size_t g = 0; g < meshes.size(); ++g)
      brute.push_back(bruteObject(meshes[g], glm::dmat4(1.0), scene->renderOrigin(), uint32_t(g)));
  }
};

TEST(Layers, SphereStackEqualsSortedBruteForceForBothMethodsAndEveryPacketWidth) {
  MethodGuard guard;
  const SphereStack stack;
  AovSet two;
  two.layers = 2;
  Framebuffer small(4, 4, two);
  ASSERT_EQ(LayerPlan(*stack.scene, *makeCamera(stackCamera(), stack.scene->renderOrigin()), small,
                      glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, -1.0f), LayerMethod::Filter)
                .method,
            LayerMethod::Filter)
      << "the filter method must run on a scene built with contextFilter";
  for (LayerMethod method : {LayerMethod::Filter, LayerMethod::Retrace})
    for (int packet : {1, 4, 8, 16}) {
      // K = 10 exceeds the deepest ray (8 surfaces): the rest must be misses. K = 3 cuts the
      // list short, where the filter's early acceptance of the K-th hit matters.
      const int deep =
          expectLayersMatchBruteForce(*stack.scene, stack.brute, stackCamera(), 10, packet, method);
      EXPECT_GT(deep, 1000);
      expectLayersMatchBruteForce(*stack.scene, stack.brute, stackCamera(), 3, packet, method);
    }
}

TEST(Layers, SomeRaysCrossEightSurfaces) {
  // The fixture must exercise deep lists: a ray through all four spheres.
  const SphereStack stack;
  const CameraParams p = stackCamera();
  const auto cam = makeCamera(p, stack.scene->renderOrigin());
  size_t deepest = 0;
  for (int i = 0; i < p.height; ++i)
    for (int j = 0; j < p.width; ++j) {
      const CentreRay r = centreRayOf(*cam, i, j);
      deepest = std::max(deepest, bruteForce(stack.brute, r.org, r.dir).hits.size());
    }
  EXPECT_EQ(deepest, 8u);
}

void expectLayerZeroEqualsAovs(const Framebuffer& fb, const std::string& what) {
  const size_t n = fb.pixelCount();
  int hits = 0;
  for (size_t p = 0; p < n; ++p) {
    EXPECT_EQ(std::memcmp(&fb.layerDepth[p], &fb.depth[p], 4), 0) << what << " pixel " << p;
    EXPECT_EQ(std::memcmp(&fb.layerDistance[p], &fb.distance[p], 4), 0) << what << " pixel " << p;
    EXPECT_EQ(fb.layerPrimId[p], fb.primId[p]) << what << " pixel " << p;
    EXPECT_EQ(fb.layerGeomId[p], fb.geomId[p]) << what << " pixel " << p;
    hits += fb.geomId[p] != kInvalidId;
  }
  EXPECT_GT(hits, int(n / 4)) << what;
}

TEST(Layers, LayerZeroEqualsTheGeometryAovsBitForBit) {
  MethodGuard guard;
  const SphereStack stack;
  CameraParams lens = stackCamera();
  lens.type = "thinlens";
  lens.apertureRadius = 0.2;
  lens.focusDistance = 10;
  lens.spp = 4;
  for (LayerMethod method : {LayerMethod::Filter, LayerMethod::Retrace})
    for (int packet : {1, 8, 16}) {
      // spp 1 with colour: the geometry comes from sample 0; thin lens at spp 4: from an
      // extra centre-ray pass.
      expectLayerZeroEqualsAovs(
          renderLayers(*stack.scene, stackCamera(), 4, parseAovList("all"), packet, method),
          cat(layerMethodName(method), " packet ", packet));
      expectLayerZeroEqualsAovs(
          renderLayers(*stack.scene, lens, 4, parseAovList("all"), packet, method),
          cat(layerMethodName(method), " thinlens packet ", packet));
    }
}

TEST(Layers, CulledInstancedSceneReportsOriginalPrimIdsAndInstanceIds) {
  MethodGuard guard;
  const Mesh sphere = worldMesh("procedural:sphere?radius=1&segments=22&rings=11");
  // Drop the triangles facing away from +x (as a culler might): primIDs of the kept ones are
  // not their Embree indices, so a missing remap shows.
  TriangleSubset subset;
  for (size_t t = 0; t < sphere.triangleCount(); ++t) {
    const glm::vec3 c = sphere.vertex(sphere.indices[3 * t]) +
                        sphere.vertex(sphere.indices[3 * t + 1]) +
                        sphere.vertex(sphere.indices[3 * t + 2]);
    if (c.x < -0.9f) continue;
    for (int k = 0; k < 3; ++k) subset.indices.push_back(sphere.indices[3 * t + size_t(k)]);
    subset.primIds.push_back(uint32_t(t));
  }
  ASSERT_LT(subset.triangleCount(), sphere.triangleCount());
  std::vector<SceneObject> objects;
  for (double z : {2.5, 0.0, -2.5})
    objects.push_back({&sphere,
                       glm::scale(glm::translate(glm::dmat4(1.0), glm::dvec3(0.05 * z, 0.0, z)),
                                  glm::dvec3(1.0 + 0.1 * z)),
                       &subset});
  const Scene scene(test::numericsDevice(), objects, withFilter());
  ASSERT_EQ(scene.instanceCount(), 3u);
  ASSERT_TRUE(scene.remapsPrimIds());
  std::vector<BruteObject> brute;
  for (size_t k = 0; k < objects.size(); ++k)
    brute.push_back(
        bruteObject(sphere, objects[k].worldFromMesh, scene.renderOrigin(), uint32_t(k), &subset));
  for (LayerMethod method : {LayerMethod::Filter, LayerMethod::Retrace})
    for (int packet : {1, 16})
      EXPECT_GT(expectLayersMatchBruteForce(scene, brute, stackCamera(), 7, packet, method), 500);
}

TEST(Layers, CoincidentSurfacesAreTwoLayersByFilterAndOneByRetracing) {
  // The documented difference: two identical quads at the same depth.
  MethodGuard guard;
  const Mesh a = worldMesh("procedural:quad?size=4"), b = worldMesh("procedural:quad?size=4");
  const Scene scene(test::numericsDevice(), std::vector<const Mesh*>{&a, &b}, withFilter());
  CameraParams p = stackCamera();
  p.width = p.height = 8;
  const size_t centre = 4 * 8 + 4, n = 64;
  const Framebuffer byFilter = renderLayers(scene, p, 3, kAovDepth, 16, LayerMethod::Filter);
  EXPECT_EQ(byFilter.layerDistance[centre], byFilter.layerDistance[n + centre]);
  EXPECT_NE(byFilter.layerGeomId[centre], byFilter.layerGeomId[n + centre]);
  EXPECT_EQ(byFilter.layerGeomId[2 * n + centre], kInvalidId);
  const Framebuffer byRetrace = renderLayers(scene, p, 3, kAovDepth, 16, LayerMethod::Retrace);
  EXPECT_EQ(byRetrace.layerDistance[centre], byFilter.layerDistance[centre]);
  EXPECT_EQ(byRetrace.layerGeomId[n + centre], kInvalidId);
}

TEST(Layers, FilterFallsBackToRetracingOnASceneWithoutContextFilter) {
  const Mesh m = worldMesh("procedural:sphere");
  const Scene plain(test::numericsDevice(), std::vector<const Mesh*>{&m});
  const auto cam = makeCamera(stackCamera(), plain.renderOrigin());
  AovSet set(kAovDepth);
  set.layers = 2;
  Framebuffer fb(4, 4, set);
  EXPECT_EQ(
      LayerPlan(plain, *cam, fb, glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, -1.0f), LayerMethod::Filter)
          .method,
      LayerMethod::Retrace);
}

TEST(Layers, CountAndMethodNamesAreChecked) {
  EXPECT_NO_THROW(checkLayerCount(1, "--layers"));
  EXPECT_NO_THROW(checkLayerCount(kMaxLayers, "--layers"));
  EXPECT_THROW(checkLayerCount(0, "--layers"), Error);
  EXPECT_THROW(checkLayerCount(kMaxLayers + 1, "--layers"), Error);
  EXPECT_EQ(parseLayerMethod("retrace"), LayerMethod::Retrace);
  EXPECT_EQ(parseLayerMethod("filter"), LayerMethod::Filter);
  try {
    parseLayerMethod("filtre");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'filter'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace aperture
