// Closest points (core/queries/closest_points.h) against a brute force in double over every
// triangle, computed independently (tests/query_support.h): random points near and far from a
// procedural sphere and the bunny, points exactly at vertices and on edges, instanced and
// chunked scenes, non-finite points and an empty scene.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/queries/closest_points.h"
#include "core/util/error.h"
#include "tests/numerics_support.h"
#include "tests/query_support.h"
#include "tests/support.h"

namespace aperture {
namespace closest_points_test {

using test::queries::WorldTriangle;

namespace {

/// The largest |coordinate| of the triangles: the scale of the absolute tolerance.
double extentOf(const std::vector<WorldTriangle>& tris) {
  double e = 0;
  for (const WorldTriangle& t : tris)
    for (const glm::dvec3& v : t.v)
      e = std::max({e, std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
  return e;
}

/// Random points: near (a vertex moved by up to `near` in each axis) and far (anywhere in the
/// triangles' box grown threefold), half each.
std::vector<double> randomPoints(const std::vector<WorldTriangle>& tris, size_t n, double near,
                                 unsigned seed) {
  std::mt19937_64 rng(seed);
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const WorldTriangle& t : tris)
    for (const glm::dvec3& v : t.v) lo = glm::min(lo, v), hi = glm::max(hi, v);
  const glm::dvec3 centre = 0.5 * (lo + hi), half = 1.5 * (hi - lo);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<size_t> pick(0, tris.size() - 1);
  std::vector<double> out;
  for (size_t k = 0; k < n; ++k) {
    glm::dvec3 p;
    if (k % 2 == 0)
      p = tris[pick(rng)].v[k % 3] + near * glm::dvec3(unit(rng), unit(rng), unit(rng));
    else
      p = centre + half * glm::dvec3(unit(rng), unit(rng), unit(rng));
    out.insert(out.end(), {p.x, p.y, p.z});
  }
  return out;
}

/// Every answer equals the brute force's distance (1e-6 relative, or 1e-12 of the scene's
/// extent for points on the surface), and its point lies on its triangle, at that distance,
/// where the barycentric weights put it.
void expectExact(const Scene& scene, const std::vector<double>& pts, const std::string& what) {
  const std::vector<WorldTriangle> tris = test::queries::worldTriangles(scene);
  const double extent = extentOf(tris);
  const size_t n = pts.size() / 3;
  const ClosestPoints r = closestPoints(scene, pts.data(), n);
  ASSERT_EQ(r.distance.size(), n);
  EXPECT_EQ(r.nonFinite, 0u);
  int failures = 0;
  for (size_t k = 0; k < n && failures < 5; ++k) {
    const glm::dvec3 p(pts[3 * k], pts[3 * k + 1], pts[3 * k + 2]);
    const double want = test::queries::bruteForceDistance(p, tris);
    const double tol = 1e-6 * want + 1e-12 * extent;
    const glm::dvec3 q(r.points[3 * k], r.points[3 * k + 1], r.points[3 * k + 2]);
    const WorldTriangle* tri = nullptr;
    for (const WorldTriangle& t : tris)
      if (t.object == r.geomId[k] && t.primId == r.primId[k]) tri = &t;
    ASSERT_NE(tri, nullptr) << what << " point " << k;
    const glm::dvec3 fromWeights = r.barycentric[3 * k] * tri->v[0] +
                                   r.barycentric[3 * k + 1] * tri->v[1] +
                                   r.barycentric[3 * k + 2] * tri->v[2];
    const bool ok = std::fabs(r.distance[k] - want) <= tol &&
                    std::fabs(glm::length(p - q) - r.distance[k]) <= tol &&
                    test::queries::triangleDistance(q, tri->v) <= 1e-12 * extent &&
                    glm::length(fromWeights - q) <= 1e-12 * extent;
    if (!ok) ++failures;
    EXPECT_TRUE(ok) << what << " point " << k << " (" << p.x << ", " << p.y << ", " << p.z
                    << "): distance " << r.distance[k] << ", brute force " << want << ", |p - q| "
                    << glm::length(p - q) << ", q off its triangle by "
                    << test::queries::triangleDistance(q, tri->v) << ", weights off by "
                    << glm::length(fromWeights - q);
  }
}

/// Every vertex of the mesh, the midpoint of every edge and a random point on each edge.
std::vector<double> verticesAndEdges(const std::vector<WorldTriangle>& tris, size_t limit) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> out;
  for (size_t t = 0; t < tris.size() && out.size() < 3 * limit; t += 1 + tris.size() / limit) {
    const auto& v = tris[t].v;
    for (int c = 0; c < 3; ++c) {
      const glm::dvec3 a = v[size_t(c)], b = v[size_t((c + 1) % 3)];
      const glm::dvec3 mid = 0.5 * (a + b), any = a + unit(rng) * (b - a);
      out.insert(out.end(), {a.x, a.y, a.z, mid.x, mid.y, mid.z, any.x, any.y, any.z});
    }
  }
  return out;
}

BuildOptions chunksOf(size_t triangles) {
  BuildOptions b;
  b.bvhChunkTriangles = triangles;
  b.maxChunksPerCell = INFINITY;
  return b;
}

void expectSameAnswers(const ClosestPoints& a, const ClosestPoints& b, const std::string& what) {
  ASSERT_EQ(a.distance.size(), b.distance.size());
  for (size_t k = 0; k < a.distance.size(); ++k) {
    EXPECT_EQ(a.distance[k], b.distance[k]) << what << " point " << k;
    EXPECT_EQ(a.primId[k], b.primId[k]) << what << " point " << k;
    EXPECT_EQ(a.geomId[k], b.geomId[k]) << what << " point " << k;
  }
}

}  // namespace

TEST(ClosestPoints, TrianglePointMatchesProjectionOrEdges) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    double v[4][3];
    for (auto& x : v)
      for (double& c : x) c = unit(rng);
    const TrianglePoint q = closestPointOnTriangle(v[3], v[0], v[1], v[2]);
    const std::array<glm::dvec3, 3> tri{glm::dvec3(v[0][0], v[0][1], v[0][2]),
                                        glm::dvec3(v[1][0], v[1][1], v[1][2]),
                                        glm::dvec3(v[2][0], v[2][1], v[2][2])};
    const glm::dvec3 p(v[3][0], v[3][1], v[3][2]), at(q.x, q.y, q.z);
    const double want = test::queries::triangleDistance(p, tri);
    ASSERT_NEAR(glm::length(p - at), want, 1e-12) << "triangle " << i;
    ASSERT_NEAR(q.wa + q.wb + q.wc, 1.0, 1e-12);
    ASSERT_GE(std::min({q.wa, q.wb, q.wc}), -1e-12);
  }
}

TEST(ClosestPoints, DegenerateTriangleGivesItsSegment) {
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {2, 0, 0}, p[3] = {1.5, 1, 0};
  const TrianglePoint q = closestPointOnTriangle(p, a, b, c);
  EXPECT_NEAR(q.x, 1.5, 1e-15);
  EXPECT_NEAR(q.y, 0.0, 1e-15);
}

TEST(ClosestPoints, SphereMatchesBruteForce) {
  const Mesh mesh = loadMesh("procedural:sphere?radius=2&segments=24&rings=12&cx=100&cy=-3");
  const Scene scene(test::numericsDevice(), std::vector<const Mesh*>{&mesh});
  const std::vector<WorldTriangle> tris = test::queries::worldTriangles(scene);
  expectExact(scene, randomPoints(tris, 2000, 0.05, 1), "sphere, random");
  expectExact(scene, verticesAndEdges(tris, 400), "sphere, vertices and edges");
}

TEST(ClosestPoints, BunnyMatchesBruteForce) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const Mesh mesh = loadMesh(path);
  const Scene scene(test::numericsDevice(), std::vector<const Mesh*>{&mesh});
  const std::vector<WorldTriangle> tris = test::queries::worldTriangles(scene);
  expectExact(scene, randomPoints(tris, 300, 0.002, 2), "bunny, random");
  expectExact(scene, verticesAndEdges(tris, 60), "bunny, vertices and edges");
}

TEST(ClosestPoints, InstancesMatchBruteForce) {
  // One mesh placed three times (Embree instances): as is, rotated and scaled unevenly (not a
  // similarity), and moved far away.
  const Mesh mesh = loadMesh("procedural:sphere?radius=1&segments=16&rings=8");
  glm::dmat4 skewed(1.0);
  skewed = glm::translate(skewed, glm::dvec3(3, 0, 0));
  skewed = glm::rotate(skewed, 0.7, glm::dvec3(0.3, 1, 0.2));
  skewed = glm::scale(skewed, glm::dvec3(1.0, 2.5, 0.5));
  const glm::dmat4 far = glm::translate(glm::dmat4(1.0), glm::dvec3(0, 1e4, 0));
  ObjectIds second;
  second.instance = 7;
  const Scene scene(test::numericsDevice(),
                    std::vector<SceneObject>{SceneObject(&mesh, glm::dmat4(1.0)),
                                             SceneObject(&mesh, skewed, nullptr, second),
                                             SceneObject(&mesh, far)});
  ASSERT_GT(scene.instanceCount(), 0u);
  const std::vector<WorldTriangle> tris = test::queries::worldTriangles(scene);
  expectExact(scene, randomPoints(tris, 1500, 0.1, 4), "instances");
  // Right beside the skewed copy: its instance id is reported.
  const double p[3] = {3, 0, 0};
  const ClosestPoints r = closestPoints(scene, p, 1);
  EXPECT_EQ(r.geomId[0], 1u);
  EXPECT_EQ(r.instance[0], 7u);
}

TEST(ClosestPoints, ChunkedSceneGivesTheWholeScenesAnswers) {
  const Mesh mesh = loadMesh("procedural:sphere?radius=1&segments=64&rings=48");
  const Scene whole(test::numericsDevice(), std::vector<const Mesh*>{&mesh}, chunksOf(0));
  const Scene chunked(test::numericsDevice(), std::vector<const Mesh*>{&mesh}, chunksOf(1024));
  ASSERT_GT(chunked.stats().chunks, 1u);
  const std::vector<WorldTriangle> tris = test::queries::worldTriangles(whole);
  std::vector<double> pts = randomPoints(tris, 2000, 0.05, 5);
  const std::vector<double> exact = verticesAndEdges(tris, 300);
  pts.insert(pts.end(), exact.begin(), exact.end());
  expectExact(chunked, pts, "chunked");
  expectSameAnswers(closestPoints(whole, pts.data(), pts.size() / 3),
                    closestPoints(chunked, pts.data(), pts.size() / 3), "chunked vs whole");
}

TEST(ClosestPoints, NonFinitePointsGiveNanForThemOnly) {
  const Mesh mesh = loadMesh("procedural:cube?size=2");
  const Scene scene(test::numericsDevice(), std::vector<const Mesh*>{&mesh});
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  const std::vector<double> pts = {0, 0, 3, nan, 0, 0, 0, inf, 0, 1e300, 0, 0, 0, 0, -5};
  const ClosestPoints r = closestPoints(scene, pts.data(), 5);
  EXPECT_EQ(r.nonFinite, 3u);
  EXPECT_DOUBLE_EQ(r.distance[0], 2.0);
  EXPECT_DOUBLE_EQ(r.distance[4], 4.0);
  for (size_t k : {1, 2, 3}) {
    EXPECT_TRUE(std::isnan(r.distance[k])) << k;
    EXPECT_TRUE(std::isnan(r.points[3 * k])) << k;
    EXPECT_EQ(r.primId[k], ClosestPoints::kNoPrim) << k;
  }
}

TEST(ClosestPoints, SceneWithoutTrianglesIsAnError) {
  Mesh empty;
  empty.name = "empty";
  finishMesh(empty, LoadOptions{});
  const Scene scene(test::numericsDevice(), std::vector<const Mesh*>{&empty});
  const double p[3] = {0, 0, 0};
  const std::string e = test::errorOf([&] { closestPoints(scene, p, 1); });
  EXPECT_NE(e.find("no triangle"), std::string::npos) << e;
}

}  // namespace closest_points_test
}  // namespace aperture
