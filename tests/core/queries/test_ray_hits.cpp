// Intersection counts and lists along rays (core/queries/ray_hits.h) against closed forms:
// rays through a tessellated sphere hit it twice when they pass inside its inscribed sphere,
// never when they pass outside its circumscribed one, once from inside; a cube in chunks
// and as instances counts the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/queries/ray_hits.h"
#include "tests/numerics_support.h"

namespace aperture {
namespace ray_hits_test {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// A random unit vector.
glm::dvec3 randomDirection(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    const glm::dvec3 d(g(rng), g(rng), g(rng));
    if (glm::length(d) > 1e-3) return glm::normalize(d);
  }
}

/// A ray from distance 10 of `centre`, aimed so that it passes `b` from it (its impact
/// parameter), direction scaled by `scale`.
void rayWithImpact(std::mt19937_64& rng, const glm::dvec3& centre, double b, double scale,
                   std::vector<double>& origins, std::vector<double>& dirs) {
  const glm::dvec3 d = randomDirection(rng);
  glm::dvec3 side = glm::normalize(glm::cross(d, randomDirection(rng)));
  const glm::dvec3 o = centre - 10.0 * d + b * side;
  origins.insert(origins.end(), {o.x, o.y, o.z});
  dirs.insert(dirs.end(), {scale * d.x, scale * d.y, scale * d.z});
}

}  // namespace

TEST(RayHits, SphereIsCrossedTwiceInsideItsInscribedSphereAndMissedOutside) {
  const double radius = 2.0;
  const int segments = 48, rings = 24;
  const Mesh mesh = loadMesh("procedural:sphere?radius=2&segments=48&rings=24&cx=50&cy=1&cz=-4");
  const Scene scene(test::numericsDevice(), std::vector<const Mesh*>{&mesh});
  const glm::dvec3 centre(50, 1, -4);
  // Every point of the triangles lies between these radii (core/mesh/procedural.cpp).
  const double inscribed = radius * std::cos(kPi / (2 * rings)) * std::cos(kPi / segments);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> origins, dirs;
  std::vector<uint32_t> want;
  for (int i = 0; i < 3000; ++i) {
    const bool through = i % 2 == 0;
    const double b = through ? 0.97 * inscribed * unit(rng) : radius * (1.01 + unit(rng));
    rayWithImpact(rng, centre, b, 0.5 + 2 * unit(rng), origins, dirs);
    want.push_back(through ? 2 : 0);
  }
  // From the centre: once.
  for (int i = 0; i < 500; ++i) {
    const glm::dvec3 d = randomDirection(rng);
    origins.insert(origins.end(), {centre.x, centre.y, centre.z});
    dirs.insert(dirs.end(), {d.x, d.y, d.z});
    want.push_back(1);
  }
  const size_t n = want.size();
  size_t nonFinite = 7;
  EXPECT_EQ(countIntersections(scene, origins.data(), dirs.data(), n, &nonFinite), want);
  EXPECT_EQ(nonFinite, 0u);

  const RayHitList list = listIntersections(scene, origins.data(), dirs.data(), n);
  ASSERT_EQ(list.offsets.size(), n + 1);
  for (size_t k = 0; k < n; ++k) {
    ASSERT_EQ(list.offsets[k + 1] - list.offsets[k], want[k]) << "ray " << k;
    const glm::dvec3 o(origins[3 * k], origins[3 * k + 1], origins[3 * k + 2]),
        d(dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]);
    double previous = -1;
    for (uint64_t h = list.offsets[k]; h < list.offsets[k + 1]; ++h) {
      EXPECT_GT(list.t[h], previous) << "ray " << k << ": hits nearest first";
      previous = list.t[h];
      const double r = glm::length(o + list.t[h] * d - centre);
      EXPECT_GE(r, inscribed * (1 - 1e-5)) << "ray " << k;
      EXPECT_LE(r, radius * (1 + 1e-5)) << "ray " << k;
      EXPECT_LT(list.primId[h], mesh.triangleCount());
      EXPECT_EQ(list.geomId[h], 0u);
    }
  }
}

TEST(RayHits, ChunksAndInstancesCountAsTheWholeMesh) {
  const Mesh mesh = loadMesh("procedural:sphere?radius=1&segments=64&rings=48");
  BuildOptions chunks;
  chunks.bvhChunkTriangles = 1024;
  chunks.maxChunksPerCell = INFINITY;
  const Scene chunked(test::numericsDevice(), std::vector<const Mesh*>{&mesh}, chunks);
  ASSERT_GT(chunked.stats().chunks, 1u);
  // Two copies, the second 5 units along x: a ray along x through both crosses 4 surfaces.
  const glm::dmat4 moved =
      glm::dmat4(1.0) * glm::dmat4(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 1, 0, 0),
                                   glm::dvec4(0, 0, 1, 0), glm::dvec4(5, 0, 0, 1));
  const Scene twice(
      test::numericsDevice(),
      std::vector<SceneObject>{SceneObject(&mesh, glm::dmat4(1.0)), SceneObject(&mesh, moved)});
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  std::vector<double> origins, dirs;
  for (int i = 0; i < 500; ++i) {
    origins.insert(origins.end(), {-10.0, unit(rng), unit(rng)});
    dirs.insert(dirs.end(), {1.0, 0.0, 0.0});
  }
  for (uint32_t c : countIntersections(chunked, origins.data(), dirs.data(), 500)) ASSERT_EQ(c, 2u);
  for (uint32_t c : countIntersections(twice, origins.data(), dirs.data(), 500)) ASSERT_EQ(c, 4u);
  const RayHitList list = listIntersections(twice, origins.data(), dirs.data(), 1);
  ASSERT_EQ(list.geomId.size(), 4u);
  EXPECT_EQ(list.geomId[0], 0u);
  EXPECT_EQ(list.geomId[3], 1u);
}

TEST(RayHits, RaysThatCannotBeTracedCountNothing) {
  const Mesh mesh = loadMesh("procedural:cube?size=2");
  const Scene scene(test::numericsDevice(), std::vector<const Mesh*>{&mesh});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> origins = {0.1, 0.3, 5, nan, 0, 5, 0, 0, 5, 0.1, -0.3, 5};
  const std::vector<double> dirs = {0, 0, -1, 0, 0, -1, 0, 0, 0, 0, 0.3, -1};
  size_t nonFinite = 0;
  const std::vector<uint32_t> c =
      countIntersections(scene, origins.data(), dirs.data(), 4, &nonFinite);
  EXPECT_EQ(c, (std::vector<uint32_t>{2, 0, 0, 2}));
  EXPECT_EQ(nonFinite, 2u);
}

/// Rays from a grid around [-1, 1]³ along the axes, the faces' and the cube's diagonals, and
/// rays from random origins aimed exactly at the mesh's vertices and edge midpoints: many run
/// through edges and vertices, where two triangles may be hit at one t or a float apart.
void edgeAndVertexRays(const Mesh& mesh, std::vector<double>& origins, std::vector<double>& dirs) {
  const std::vector<glm::dvec3> axes = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0},
                                        {0, 1, 1}, {1, 0, 1}, {1, 1, 1}, {1, -1, 1}};
  for (int i = 0; i <= 12; ++i)
    for (int j = 0; j <= 12; ++j)
      for (const glm::dvec3& a : axes) {
        const double u = -1.5 + 0.25 * i, v = -1.5 + 0.25 * j;
        const glm::dvec3 o = glm::dvec3(u, v, -1.5 + 0.125 * (i + j) / 2.0) - 3.0 * a;
        origins.insert(origins.end(), {o.x, o.y, o.z});
        dirs.insert(dirs.end(), {a.x, a.y, a.z});
      }
  std::mt19937_64 rng(44);
  std::vector<glm::dvec3> targets;
  for (size_t v = 0; v < mesh.vertexCount; ++v)
    targets.push_back(mesh.anchor + glm::dvec3(mesh.vertex(v)));
  for (size_t t = 0; t < mesh.triangleCount(); t += 3)
    targets.push_back(mesh.anchor + 0.5 * glm::dvec3(mesh.vertex(mesh.indices[3 * t]) +
                                                     mesh.vertex(mesh.indices[3 * t + 1])));
  for (const glm::dvec3& target : targets) {
    const glm::dvec3 d = randomDirection(rng), o = target - 4.0 * d;
    origins.insert(origins.end(), {o.x, o.y, o.z});
    dirs.insert(dirs.end(), {d.x, d.y, d.z});
  }
}

TEST(RayHits, OneTraversalCountsEqualRetraceThroughEdgesAndVertices) {
  for (const char* spec : {"procedural:cube?size=2", "procedural:sphere?segments=32&rings=16"}) {
    const Mesh mesh = loadMesh(spec);
    BuildOptions filter;
    filter.contextFilter = true;
    const Scene retraced(test::numericsDevice(), std::vector<const Mesh*>{&mesh});
    const Scene oneTraversal(test::numericsDevice(), std::vector<const Mesh*>{&mesh}, filter);
    std::vector<double> origins, dirs;
    edgeAndVertexRays(mesh, origins, dirs);
    const size_t n = origins.size() / 3;
    size_t skippedA = 0, skippedB = 0;
    const std::vector<uint32_t> a =
        countIntersections(retraced, origins.data(), dirs.data(), n, &skippedA);
    const std::vector<uint32_t> b =
        countIntersections(oneTraversal, origins.data(), dirs.data(), n, &skippedB);
    EXPECT_EQ(b, a) << spec;
    EXPECT_EQ(skippedB, skippedA) << spec;
    // The rays do cross the surface: counts are not all zero.
    EXPECT_GT(std::count_if(a.begin(), a.end(), [](uint32_t c) { return c >= 2; }), 100) << spec;
  }
}

}  // namespace ray_hits_test
}  // namespace aperture
