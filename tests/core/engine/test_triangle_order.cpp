// Triangles put in spatial order for chunked builds (issue 13, item 3): a mesh whose triangle
// order is scattered in space is moved along a Morton curve, built in chunks, and reports
// every AOV, trace, layer and visibility result exactly as the mesh in its loaded order built
// as one BVH does: primIDs and face results stay in the loaded order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/layers.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/engine/triangle_order.h"
#include "core/exr/exr.h"
#include "core/io/ply_writer.h"
#include "core/mesh/mesh.h"
#include "core/queries/trace.h"
#include "core/queries/visibility.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

constexpr size_t kChunk = 3000;

/// 20000 triangles of spheres in a random order, with a face property (a hash of the loaded
/// index), a vertex property and vertex normals (the positions, not unit), so every AOV that
/// reads mesh data by triangle shows a wrong index.
Mesh scatteredSpheres() {
  Mesh m = loadMesh("procedural:spheres?tris=20000");
  const size_t n = m.triangleCount();
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937 random(13);
  for (size_t k = n - 1; k > 0; --k) std::swap(order[k], order[random() % (k + 1)]);
  std::vector<uint32_t> indices(3 * n);
  for (size_t k = 0; k < n; ++k)
    for (size_t c = 0; c < 3; ++c) indices[3 * k + c] = m.indices[3 * order[k] + c];
  m.indices.assign(indices.begin(), indices.end());
  MeshProperty part{PropertyDomain::Face, "part", {}}, id{PropertyDomain::Vertex, "id", {}};
  for (size_t t = 0; t < n; ++t) part.values.push_back(uint32_t(t) * 2654435761u);
  for (size_t v = 0; v < m.vertexCount; ++v) id.values.push_back(uint32_t(v));
  m.properties = {part, id};
  m.vertexNormals.assign(m.positions.begin(), m.positions.begin() + 3 * long(m.vertexCount));
  return m;
}

Mesh inSpatialOrder(Mesh m) {
  orderTrianglesInSpace(m);
  return m;
}

BuildOptions chunksOf(size_t triangles) {
  BuildOptions b;
  b.bvhChunkTriangles = triangles;
  return b;
}

CameraParams view() {
  return test::cameraParamsFromFlags("--eye 0,0.12,0.45 --at 0,0.12,0 --size 160,120 --fov 50");
}

AovSet everyAov() { return parseAovSet("all,face.part,vertex.id"); }

TEST(TriangleOrder, MovesWholeTrianglesAndRecordsTheirLoadedIndex) {
  const Mesh loaded = scatteredSpheres();
  const Mesh ordered = inSpatialOrder(loaded);
  const size_t n = loaded.triangleCount();
  ASSERT_EQ(ordered.sourceTriangles.size(), n);
  std::vector<uint32_t> sorted = ordered.sourceTriangles;
  std::sort(sorted.begin(), sorted.end());
  for (size_t t = 0; t < n; ++t) ASSERT_EQ(sorted[t], t) << "not a permutation";
  const std::vector<uint32_t> stored = storedTriangles(ordered);
  for (size_t t = 0; t < n; ++t) {
    const uint32_t s = ordered.sourceTriangle(t);
    ASSERT_EQ(stored[s], t);
    for (size_t c = 0; c < 3; ++c) ASSERT_EQ(ordered.indices[3 * t + c], loaded.indices[3 * s + c]);
    ASSERT_EQ(ordered.properties[0].values[t], loaded.properties[0].values[s]) << "face property";
  }
  EXPECT_EQ(ordered.properties[1].values, loaded.properties[1].values) << "vertex property";
  EXPECT_EQ(ordered.positions, loaded.positions);
  EXPECT_TRUE(storedTriangles(loaded).empty());
  EXPECT_EQ(loaded.sourceTriangle(7), 7u);
  // A second pass finds them in order and keeps the loaded indices (composed, not replaced).
  const Mesh twice = inSpatialOrder(ordered);
  EXPECT_EQ(twice.indices, ordered.indices);
  EXPECT_EQ(twice.sourceTriangles, ordered.sourceTriangles);
}

/// Bit k of `v` at bit 3k (an independent spelling of the Morton interleave).
uint32_t everyThirdBit(uint32_t v) {
  uint32_t out = 0;
  for (uint32_t k = 0; k < 10; ++k)
    if (v & (1u << k)) out += 1u << (3 * k);
  return out;
}

// More triangles than one block of the parallel counting sort (2^22): the order is exactly a
// stable sort by the Morton code of the 32³ cell of the centroid, computed here apart.
TEST(TriangleOrder, TheOrderIsAStableSortByTheCentroidsMortonCell) {
  Mesh m = loadMesh("procedural:spheres?tris=4500000");
  const size_t n = m.triangleCount();
  ASSERT_GT(n, size_t(1) << 22);
  std::mt19937 random(7);
  for (size_t k = n - 1; k > 0; --k) {
    const size_t other = random() % (k + 1);
    for (size_t c = 0; c < 3; ++c) std::swap(m.indices[3 * k + c], m.indices[3 * other + c]);
  }
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  std::vector<uint32_t> key(n);
  for (size_t t = 0; t < n; ++t) {
    const glm::vec3 g = (m.vertex(m.indices[3 * t]) + m.vertex(m.indices[3 * t + 1]) +
                         m.vertex(m.indices[3 * t + 2])) /
                        3.0f;
    const glm::ivec3 cell =
        glm::clamp(glm::ivec3((g - lo) * (32.0f / glm::max(hi - lo, glm::vec3(1e-30f)))), 0, 31);
    key[t] = everyThirdBit(uint32_t(cell.x)) + 2 * everyThirdBit(uint32_t(cell.y)) +
             4 * everyThirdBit(uint32_t(cell.z));
  }
  std::vector<uint32_t> want(n);
  std::iota(want.begin(), want.end(), 0u);
  std::stable_sort(want.begin(), want.end(),
                   [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
  const Mesh ordered = inSpatialOrder(m);
  EXPECT_EQ(ordered.sourceTriangles, want);
  EXPECT_LE(chunksPerCell(ordered, ordered.indices.data(), n, n / 6), kMaxChunksPerCell);
}

TEST(TriangleOrder, TheSpatialOrderKeepsChunksApart) {
  const Mesh loaded = scatteredSpheres();
  const Mesh ordered = inSpatialOrder(loaded);
  const size_t n = loaded.triangleCount();
  const double before = chunksPerCell(loaded, loaded.indices.data(), n, kChunk);
  const double after = chunksPerCell(ordered, ordered.indices.data(), n, kChunk);
  EXPECT_GT(before, 1.5);
  EXPECT_LE(after, kMaxChunksPerCell);
  // orderIfScattered moves only what the chunk rule would build whole, as orderTrianglesInSpace.
  Mesh copy = loaded;
  EXPECT_TRUE(orderIfScattered(copy, chunksOf(kChunk)));
  EXPECT_EQ(copy.indices, ordered.indices);
  EXPECT_EQ(copy.sourceTriangles, ordered.sourceTriangles);
  EXPECT_FALSE(orderIfScattered(copy, chunksOf(kChunk))) << "already in order";
  BuildOptions compact = chunksOf(kChunk);
  compact.compact = true;
  for (const BuildOptions& keep : {chunksOf(n), chunksOf(0), compact}) {
    Mesh same = loaded;
    EXPECT_FALSE(orderIfScattered(same, keep)) << "no larger than a chunk, off, or compact";
    EXPECT_EQ(same.indices, loaded.indices);
    EXPECT_TRUE(same.sourceTriangles.empty());
  }
  // The Scene's own rule agrees: the loaded order is built whole, the spatial one in chunks.
  EXPECT_EQ(Scene(test::numericsDevice(), {&loaded}, chunksOf(kChunk)).stats().chunks, 0u);
  EXPECT_EQ(Scene(test::numericsDevice(), {&ordered}, chunksOf(kChunk)).stats().chunks,
            (n + kChunk - 1) / kChunk);
}

TEST(TriangleOrder, RendersLayersAndTracesReportTheLoadedOrder) {
  const Mesh loaded = scatteredSpheres();
  const Mesh ordered = inSpatialOrder(loaded);
  Mesh unmapped = ordered;  // the moved triangles with their loaded indices forgotten
  unmapped.sourceTriangles.clear();
  BuildOptions whole = chunksOf(0), chunks = chunksOf(kChunk);
  whole.contextFilter = chunks.contextFilter = true;  // layers by filter run on both
  const Scene one(test::numericsDevice(), {&loaded}, whole);
  const Scene split(test::numericsDevice(), {&ordered}, chunks);
  const Scene wrong(test::numericsDevice(), {&unmapped}, chunks);
  ASSERT_GT(split.stats().chunks, 1u);
  EXPECT_TRUE(split.remapsPrimIds());
  EXPECT_FALSE(split.culled());
  AovSet aovs = everyAov();
  aovs.layers = 3;
  const Framebuffer a = test::render(split, view(), aovs), b = test::render(one, view(), aovs);
  test::expectIdentical(a, b, "spatial order in chunks against the loaded order whole");
  // Without the map the primIDs (and only they) are the stored triangles': the check bites.
  const std::string differs = test::differingAovs(test::render(wrong, view(), aovs), b);
  EXPECT_NE(differs.find("primid"), std::string::npos) << differs;
  EXPECT_EQ(differs.find("face.part"), std::string::npos) << differs;

  const auto cam = makeCamera(view(), one.renderOrigin());
  std::vector<TraceRay> rays;
  for (int i = 0; i < 120; i += 3)
    for (int j = 0; j < 160; j += 3) {
      glm::dvec3 org, dir;
      if (cam->centreRayAt(j + 0.5, i + 0.5, org, dir))
        rays.push_back({glm::vec3(org), glm::vec3(dir)});
    }
  const std::vector<TraceHit> ta = traceRays(split, rays, 16), tb = traceRays(one, rays, 16);
  ASSERT_EQ(ta.size(), tb.size());
  size_t hits = 0;
  for (size_t k = 0; k < ta.size(); ++k) {
    EXPECT_EQ(ta[k].t, tb[k].t) << k;
    EXPECT_EQ(ta[k].primId, tb[k].primId) << k;
    hits += tb[k].hit();
  }
  EXPECT_GT(hits, 100u);
}

TEST(TriangleOrder, FaceVisibilityAndItsPlyKeepTheLoadedOrder) {
  const Mesh loaded = scatteredSpheres();
  const Mesh ordered = inSpatialOrder(loaded);
  const Scene one(test::numericsDevice(), {&loaded}, chunksOf(0));
  const Scene split(test::numericsDevice(), {&ordered}, chunksOf(kChunk));
  const auto near = makeCamera(view(), one.renderOrigin());
  const auto far = makeCamera(
      test::cameraParamsFromFlags("--eye 0.05,0.15,0.5 --at 0,0.12,0 --size 120,90 --fov 45"),
      one.renderOrigin());
  const std::vector<const Camera*> cams{near.get(), far.get()};
  const FaceVisibility va = faceVisibility(split, cams), vb = faceVisibility(one, cams);
  EXPECT_EQ(va.viewCount, vb.viewCount);
  EXPECT_EQ(va.pixels, vb.pixels);
  EXPECT_EQ(va.bestView, vb.bestView);
  EXPECT_EQ(va.cameraFaces.indptr, vb.cameraFaces.indptr);
  EXPECT_EQ(va.cameraFaces.indices, vb.cameraFaces.indices);
  EXPECT_EQ(va.faceCameras.indices, vb.faceCameras.indices);
  EXPECT_GT(std::count(vb.viewCount.begin(), vb.viewCount.end(), 2u), 100);
  EXPECT_GT(std::count(vb.bestView.begin(), vb.bestView.end(), 1), 100);
  // The PLY of the visibility command: the same bytes from either mesh.
  const std::string dir = test::scratchDir();
  const std::vector<PlyFaceProperty> props{{"view_count", PlyType::UInt32, vb.viewCount.data()}};
  writePlyWithFaceProperties(dir + "/a.ply", ordered, props);
  writePlyWithFaceProperties(dir + "/b.ply", loaded, props);
  EXPECT_EQ(test::readFile(dir + "/a.ply"), test::readFile(dir + "/b.ply"));
  // And the check bites: the moved faces written in stored order differ.
  Mesh unmapped = ordered;
  unmapped.sourceTriangles.clear();
  writePlyWithFaceProperties(dir + "/c.ply", unmapped, props);
  EXPECT_NE(test::readFile(dir + "/c.ply"), test::readFile(dir + "/b.ply"));
}

// The command line orders a scattered file before its build (apps/services/scene_setup.cpp) and
// writes the AOVs of its loaded order, culled or not.
TEST(TriangleOrderCli, AScatteredFileIsChunkedAndRendersAsLoaded) {
  const std::string dir = test::scratchDir(), ply = dir + "/scattered.ply";
  const Mesh loaded = scatteredSpheres();
  writePlyWithFaceProperties(ply, loaded,
                             {{"part", PlyType::UInt32, loaded.properties[0].values.data()}});
  const std::string render = test::apertureBinary() + " render --mesh " + ply +
                             " --eye 0,0.12,0.45 --at 0,0.12,0 --fov 50 --size 96,72 "
                             "--aov all,face.part --out " +
                             dir;
  std::string out;
  ASSERT_EQ(test::runCommand(render + "/one.exr --bvh-chunk 0", &out), 0) << out;
  EXPECT_EQ(out.find("spatial order"), std::string::npos) << out;
  for (const std::string cull : {"", " --cull"}) {
    ASSERT_EQ(test::runCommand(render + "/chunks.exr --bvh-chunk 1024" + cull, &out), 0) << out;
    EXPECT_NE(out.find("20000 triangles scattered in space, put in spatial order"),
              std::string::npos)
        << out;
    EXPECT_EQ(out.find(" 0 chunks"), std::string::npos) << "built in chunks: " << out;
    test::expectIdentical(readExr(dir + "/chunks.exr"), readExr(dir + "/one.exr"), "cli" + cull);
  }
  // tradeoff builds its own scenes from the loaded meshes: it orders them too.
  ASSERT_EQ(test::runCommand(test::apertureBinary() +
                                 " tradeoff --quick --reference-spp 4 --mesh " + ply +
                                 " --eye 0,0.12,0.45 --at 0,0.12,0 --fov 50 --size 48,36 "
                                 "--bvh-chunk 1024 --out-dir " +
                                 dir + " --name t",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("20000 triangles scattered in space, put in spatial order"), std::string::npos)
      << out;
}

}  // namespace
}  // namespace aperture
