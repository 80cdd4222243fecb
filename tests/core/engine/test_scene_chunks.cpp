// Chunked BVH builds (issue 13, item 3): a large mesh built as several BVHs placed by identity
// instances renders, traces, layers and counts visibility exactly as the one-BVH build does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <glm/gtc/matrix_transform.hpp>
#include <string>
#include <vector>

#include "cameras/registry/culling.h"
#include "cameras/registry/registry.h"
#include "core/engine/cull.h"
#include "core/engine/layers.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/queries/trace.h"
#include "core/queries/visibility.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// Chunks of `triangles`, whatever the mesh's order (these tests are about what the chunks
/// report; ChunkPolicy is about when they are built).
BuildOptions chunked(size_t triangles, bool robust = true) {
  BuildOptions b;
  b.robust = robust;
  b.bvhChunkTriangles = triangles;
  b.maxChunksPerCell = INFINITY;
  return b;
}

BuildOptions whole(bool robust = true) { return chunked(0, robust); }

CameraParams cityView() {
  return test::cameraParamsFromFlags("--eye 30,25,30 --at 0,0,0 --size 160,120 --fov 40");
}

CameraParams cityCloseUp() {
  return test::cameraParamsFromFlags("--eye -3,1.5,4 --at -5.6,1,-2.5 --size 160,120 --fov 35");
}

/// The largest primID in the image: a hit past the first chunk shows that chunk offsets were
/// exercised.
uint32_t largestPrimId(const Framebuffer& fb) {
  uint32_t most = 0;
  for (uint32_t id : fb.primId)
    if (id != 0xFFFFFFFFu) most = std::max(most, id);
  return most;
}

TEST(BvhChunks, EveryAovIsBitIdenticalToTheOneBvhBuild) {
  const Mesh city = loadMesh("procedural:city");
  const size_t n = city.triangleCount();
  for (bool robust : {true, false}) {
    const Scene one(test::numericsDevice(), {&city}, whole(robust));
    EXPECT_EQ(one.stats().chunks, 0u);
    EXPECT_FALSE(one.hasChunks());
    // Chunks of 100 (the last one short), a third, and just under the whole mesh.
    for (size_t size : {size_t(100), n / 3, n - 1}) {
      const Scene split(test::numericsDevice(), {&city}, chunked(size, robust));
      EXPECT_EQ(split.stats().chunks, (n + size - 1) / size) << size;
      EXPECT_TRUE(split.hasChunks());
      EXPECT_EQ(split.instanceCount(), 0u) << "chunks are not instances of the user's";
      EXPECT_EQ(split.stats().uniqueTriangles, n);
      for (const CameraParams& p : {cityView(), cityCloseUp()}) {
        const Framebuffer a = test::render(split, p), b = test::render(one, p);
        test::expectIdentical(
            a, b, "chunk " + std::to_string(size) + " robust " + std::to_string(robust));
        if (size < n - 1) {
          EXPECT_GE(largestPrimId(b), size) << "a hit past the first chunk";
        }
      }
    }
  }
}

TEST(BvhChunks, AMeshNoLargerThanAChunkAndTheCompactBvhAreBuiltWhole) {
  const Mesh city = loadMesh("procedural:city");
  EXPECT_EQ(Scene(test::numericsDevice(), {&city}, chunked(city.triangleCount())).stats().chunks,
            0u);
  BuildOptions compact = chunked(100);
  compact.compact = true;
  EXPECT_EQ(compact.effectiveChunkTriangles(), 0u);
  EXPECT_EQ(Scene(test::numericsDevice(), {&city}, compact).stats().chunks, 0u);
}

// Chunk instances take geomIDs after the objects': hits on the other objects, direct or
// instanced, keep theirs, and instanced normals still go through their instance's matrix.
TEST(BvhChunks, OtherObjectsKeepTheirGeomIdsAndNormals) {
  const Mesh city = loadMesh("procedural:city");
  const glm::dmat4 moved = glm::rotate(glm::translate(glm::dmat4(1.0), glm::dvec3(8.0, 0.37, 0.0)),
                                       0.4, glm::dvec3(0.0, 1.0, 0.0));
  // Each placement off the others' grid and height: coplanar triangles of two objects tie, and
  // a tie goes to whichever BVH Embree visits first.
  const glm::dmat4 behind = glm::translate(glm::dmat4(1.0), glm::dvec3(-7.77, -0.29, -8.31));
  Mesh second = city;  // placed twice: built once and instanced
  Mesh raised = city;  // attached directly beside the city: the same anchor, its vertices moved
  for (size_t v = 0; v < raised.vertexCount; ++v)
    for (int c = 0; c < 3; ++c) raised.positions[3 * v + size_t(c)] += (c == 1 ? 1.1f : 0.37f);
  Mesh small = loadMesh("procedural:quad");  // under the chunk size: in the top-level BVH
  const glm::dvec3 shift = city.anchor - small.anchor;
  for (size_t v = 0; v < small.vertexCount; ++v)
    for (int c = 0; c < 3; ++c) small.positions[3 * v + size_t(c)] += float(shift[c]);
  small.anchor = city.anchor;
  const std::vector<SceneObject> objects{{&small, glm::dmat4(1.0), nullptr},
                                         {&city, glm::dmat4(1.0), nullptr},
                                         {&second, moved, nullptr},
                                         {&raised, glm::dmat4(1.0), nullptr},
                                         {&second, behind, nullptr}};
  const Scene one(test::numericsDevice(), objects, whole());
  const Scene split(test::numericsDevice(), objects, chunked(150));
  EXPECT_EQ(split.stats().chunks, 2 * ((city.triangleCount() + 149) / 150));
  EXPECT_EQ(split.instanceCount(), 2u);
  std::vector<uint32_t> seen;
  for (const CameraParams& p : {cityView(), cityCloseUp()}) {
    const Framebuffer a = test::render(split, p), b = test::render(one, p);
    test::expectIdentical(a, b, "five objects");
    seen.insert(seen.end(), b.geomId.begin(), b.geomId.end());
  }
  for (uint32_t object : {0u, 1u, 2u, 3u, 4u})
    EXPECT_NE(std::find(seen.begin(), seen.end(), object), seen.end()) << "object " << object;
}

TEST(BvhChunks, CulledChunksReportTheMeshsPrimIds) {
  const Mesh city = loadMesh("procedural:city");
  const std::vector<SceneObject> objects{{&city, glm::dmat4(1.0), nullptr}};
  const CameraParams p = cityCloseUp();
  const Scene full(test::numericsDevice(), objects, whole());
  std::deque<TriangleSubset> subsets;
  std::vector<SceneObject> culledObjects = objects;
  const CameraCuller culler = cullerFor({p}, full.renderOrigin());
  const CullStats stats = cullObjects(culledObjects, culler.test(), subsets);
  ASSERT_GT(stats.trianglesKept, 60u);
  const Scene culled(test::numericsDevice(), culledObjects, chunked(stats.trianglesKept / 3));
  EXPECT_GE(culled.stats().chunks, 3u);
  EXPECT_TRUE(culled.remapsPrimIds());
  test::expectIdentical(test::render(culled, p), test::render(full, p), "culled");
}

// On spheres: the city's building floors lie on its ground, and where two triangles coincide
// the layer behind the first is a tie that either BVH may break its own way.
TEST(BvhChunks, LayersTraceAndVisibilityMatchTheOneBvhBuild) {
  const Mesh spheres = loadMesh("procedural:spheres?tris=20000");
  BuildOptions wholeFiltered = whole(), splitFiltered = chunked(3000);
  wholeFiltered.contextFilter = splitFiltered.contextFilter = true;  // LayerMethod::Filter runs
  const Scene one(test::numericsDevice(), {&spheres}, wholeFiltered);
  const Scene split(test::numericsDevice(), {&spheres}, splitFiltered);
  EXPECT_EQ(split.stats().chunks, (spheres.triangleCount() + 2999) / 3000);
  const CameraParams p =
      test::cameraParamsFromFlags("--eye 0,0.12,0.45 --at 0,0.12,0 --size 160,120 --fov 50");
  // Layers: every surface along the centre ray (the filter collects the chunks' raw hits).
  for (LayerMethod method : {LayerMethod::Filter, LayerMethod::Retrace}) {
    const LayerMethod saved = defaultLayerMethod();
    setLayerMethod(method);
    AovSet set(kAovDepth | kAovPrimId | kAovGeomId);
    set.layers = 4;
    const Framebuffer a = test::render(split, p, set), b = test::render(one, p, set);
    setLayerMethod(saved);
    test::expectIdentical(a, b, "layers by method " + std::to_string(int(method)));
    EXPECT_GE(*std::max_element(b.layerPrimId.begin(), b.layerPrimId.end(),
                                [](uint32_t x, uint32_t y) {
                                  return (x == 0xFFFFFFFFu ? 0 : x) < (y == 0xFFFFFFFFu ? 0 : y);
                                }),
              3000u);
  }
  // traceRays (the Python trace path): the centre rays of every third pixel of the view.
  const auto cam = makeCamera(p, one.renderOrigin());
  std::vector<TraceRay> rays;
  for (int i = 0; i < p.height; i += 3)
    for (int j = 0; j < p.width; j += 3) {
      glm::dvec3 org, dir;
      if (cam->centreRayAt(j + 0.5, i + 0.5, org, dir))
        rays.push_back({glm::vec3(org), glm::vec3(dir)});
    }
  for (int packet : {1, 16}) {
    const std::vector<TraceHit> a = traceRays(split, rays, packet),
                                b = traceRays(one, rays, packet);
    ASSERT_EQ(a.size(), b.size());
    size_t pastFirstChunk = 0;
    for (size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(a[k].t, b[k].t) << k;
      EXPECT_EQ(a[k].primId, b[k].primId) << k;
      EXPECT_EQ(a[k].geomId, b[k].geomId) << k;
      pastFirstChunk += b[k].primId != TraceHit::kNoHit && b[k].primId >= 3000;
    }
    EXPECT_GT(pastFirstChunk, 0u);
  }
  // Face visibility counts primIDs of object 0 from the frame loop's renders.
  const std::vector<const Camera*> cams{cam.get()};
  const FaceVisibility va = faceVisibility(split, cams), vb = faceVisibility(one, cams);
  EXPECT_EQ(va.pixels, vb.pixels);
  EXPECT_EQ(va.viewCount, vb.viewCount);
  EXPECT_GT(
      std::count_if(vb.pixels.begin() + 3000, vb.pixels.end(), [](uint64_t c) { return c > 0; }),
      0);
}

/// Four triangles: 0 and 1 near the origin, 2 and 3 far from it, in the order `order`.
Mesh twoClusters(const std::vector<uint32_t>& order) {
  Mesh m = loadMesh("procedural:quad");  // for the anchor and padding conventions
  const float at[4][3] = {{0, 0, 0}, {0.1f, 0, 0}, {10, 10, 10}, {10.1f, 10, 10}};
  m.positions.assign(3 * 12 + kVertexPaddingFloats, 0.0f);
  m.vertexCount = 12;
  m.indices.clear();
  for (uint32_t t : order) {
    for (uint32_t c = 0; c < 3; ++c) {
      const uint32_t v = 3 * t + c;
      for (int a = 0; a < 3; ++a)
        m.positions[3 * v + uint32_t(a)] =
            at[t][a] + (c == 1 && a == 1 ? 0.05f : 0.0f) + (c == 2 && a == 2 ? 0.05f : 0.0f);
      m.indices.push_back(v);
    }
  }
  return m;
}

TEST(ChunkPolicy, ChunksPerCellCountsTheRunsThatShareACell) {
  const Mesh apart = twoClusters({0, 1, 2, 3}), interleaved = twoClusters({0, 2, 1, 3});
  // Runs of 2: {0, 1} and {2, 3} keep to their own cell; {0, 2} and {1, 3} meet in both.
  EXPECT_EQ(chunksPerCell(apart, apart.indices.data(), 4, 2), 1.0);
  EXPECT_EQ(chunksPerCell(interleaved, interleaved.indices.data(), 4, 2), 2.0);
  // Runs of 1: two runs in each occupied cell, whatever the order.
  EXPECT_EQ(chunksPerCell(apart, apart.indices.data(), 4, 1), 2.0);
  // One run: 1.
  EXPECT_EQ(chunksPerCell(interleaved, interleaved.indices.data(), 4, 4), 1.0);
}

TEST(ChunkPolicy, OnlyAMeshWhoseOrderKeepsChunksApartIsBuiltInChunks) {
  const Mesh spheres = loadMesh("procedural:spheres?tris=20000");
  BuildOptions policy;  // the default maxChunksPerCell
  policy.bvhChunkTriangles = 5000;
  const Scene ordered(test::numericsDevice(), {&spheres}, policy);
  EXPECT_LE(ordered.stats().chunksPerCell, kMaxChunksPerCell);
  EXPECT_EQ(ordered.stats().chunks, (spheres.triangleCount() + 4999) / 5000);
  // The same triangles dealt out like cards: every run of 5000 spans every sphere.
  Mesh dealt = spheres;
  const size_t n = spheres.triangleCount(), runs = (n + 4999) / 5000;
  size_t next = 0;
  for (size_t r = 0; r < runs; ++r)
    for (size_t t = r; t < n; t += runs, ++next)
      for (int c = 0; c < 3; ++c)
        dealt.indices[3 * next + size_t(c)] = spheres.indices[3 * t + size_t(c)];
  ASSERT_EQ(next, n);
  const Scene scattered(test::numericsDevice(), {&dealt}, policy);
  EXPECT_GT(scattered.stats().chunksPerCell, 1.5);
  EXPECT_EQ(scattered.stats().chunks, 0u) << "built as one BVH";
  EXPECT_FALSE(scattered.hasChunks());
}

TEST(BvhChunksShared, BunnyInSevenChunksIsBitIdentical) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const Mesh bunny = loadMesh(path);
  const Scene one(test::numericsDevice(), {&bunny}, whole());
  const Scene split(test::numericsDevice(), {&bunny}, chunked(10000));
  EXPECT_EQ(split.stats().chunks, (bunny.triangleCount() + 9999) / 10000);
  const CameraParams p = test::cameraParamsFromFlags(
      "--eye -0.02,0.11,0.35 --at -0.017,0.11,0 --size 200,200 --fov 30");  // the bench's view
  const Framebuffer a = test::render(split, p), b = test::render(one, p);
  test::expectIdentical(a, b, "bunny");
  EXPECT_GE(largestPrimId(b), 60000u);
}

}  // namespace
}  // namespace aperture
