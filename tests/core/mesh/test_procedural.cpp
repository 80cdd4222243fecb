// Procedural meshes: triangle budgets, exact quad/cube, sphere accuracy, spec errors.
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <utility>

#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "tests/support.h"

namespace aperture {
namespace {

glm::dvec3 worldVertex(const Mesh& m, uint32_t k) { return m.anchor + glm::dvec3(m.vertex(k)); }

/// Every triangle's normal points away from `inside` (closed convex shapes).
void expectOutward(const Mesh& m, glm::dvec3 inside, const char* what) {
  size_t wrong = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    glm::dvec3 a = worldVertex(m, m.indices[3 * t]), b = worldVertex(m, m.indices[3 * t + 1]),
               c = worldVertex(m, m.indices[3 * t + 2]);
    glm::dvec3 n = glm::cross(b - a, c - a);
    if (glm::dot(n, (a + b + c) / 3.0 - inside) <= 0) ++wrong;
  }
  EXPECT_EQ(wrong, 0u) << what << ": inward-facing triangles";
}

/// Each undirected edge is used by exactly two triangles, once in each direction.
void expectWatertight(const Mesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    for (int e = 0; e < 3; ++e) ++edges[{m.indices[3 * t + e], m.indices[3 * t + (e + 1) % 3]}];
  for (const auto& [edge, n] : edges) {
    EXPECT_EQ(n, 1) << edge.first << "-" << edge.second;
    EXPECT_EQ(edges.count({edge.second, edge.first}), 1u) << edge.first << "-" << edge.second;
  }
}

TEST(Procedural, SpheresTriangleCountWithinOnePercent) {
  for (long n : {100L, 1000L, 12345L, 200000L, 1000003L}) {
    Mesh m = loadMesh("procedural:spheres?tris=" + std::to_string(n));
    double rel = std::fabs(double(m.triangleCount()) - double(n)) / double(n);
    EXPECT_LT(rel, 0.01) << "tris=" << n << " gave " << m.triangleCount();
    EXPECT_EQ(m.stats.degenerateTriangles, 0u);
  }
  Mesh d = loadMesh("procedural:default");
  EXPECT_NEAR(double(d.triangleCount()), 200000.0, 2000.0);
}

TEST(Procedural, SpheresSceneLayout) {
  LoadOptions world;
  world.placement = Placement::WorldSpace;
  Mesh m = loadMesh("procedural:spheres?tris=50000", world);
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  EXPECT_EQ(lo.y, 0.0f);  // spheres stand on the ground plane
  EXPECT_GT(hi.x - lo.x, 9.0f);
  EXPECT_LT(hi.x - lo.x, 13.0f);
  EXPECT_NEAR(lo.x + hi.x, 0.0f, 1e-4f);
  EXPECT_NEAR(lo.z + hi.z, 0.0f, 1e-4f);
}

TEST(Procedural, TwentyMillionTriangles) {
  Mesh m = loadMesh("procedural:spheres?tris=20000000");
  EXPECT_NEAR(double(m.triangleCount()), 2e7, 2e5);
  std::cout << "[ info ] spheres tris=20000000: " << m.triangleCount() << " triangles in "
            << m.stats.loadSeconds << " s\n";
}

TEST(Procedural, QuadExactVertices) {
  LoadOptions world;
  world.placement = Placement::WorldSpace;
  Mesh m = loadMesh("procedural:quad?size=3&z=-0.5", world);
  ASSERT_EQ(m.vertexCount, 4u);
  EXPECT_EQ(m.vertex(0), glm::vec3(-1.5, -1.5, -0.5));
  EXPECT_EQ(m.vertex(1), glm::vec3(1.5, -1.5, -0.5));
  EXPECT_EQ(m.vertex(2), glm::vec3(1.5, 1.5, -0.5));
  EXPECT_EQ(m.vertex(3), glm::vec3(-1.5, 1.5, -0.5));
  ASSERT_EQ(m.triangleCount(), 2u);
  // Both triangles face +z.
  for (size_t t = 0; t < 2; ++t) {
    glm::vec3 a = m.vertex(m.indices[3 * t]), b = m.vertex(m.indices[3 * t + 1]),
              c = m.vertex(m.indices[3 * t + 2]);
    EXPECT_GT(glm::cross(b - a, c - a).z, 0.0f);
  }
  Mesh d = loadMesh("procedural:quad");
  EXPECT_EQ(d.anchor, glm::dvec3(0));
  EXPECT_EQ(d.vertex(2), glm::vec3(1, 1, 0));
}

TEST(Procedural, SphereVerticesOnTheSphereAndWithinTheSagitta) {
  const double r = 2.5, cx = 1, cy = -2, cz = 3;
  const int segments = 24, rings = 10;
  Mesh m = loadMesh("procedural:sphere?radius=2.5&segments=24&rings=10&cx=1&cy=-2&cz=3");
  EXPECT_EQ(m.vertexCount, size_t(segments * (rings - 1) + 2));
  EXPECT_EQ(m.triangleCount(), size_t(2 * segments * (rings - 1)));
  const glm::dvec3 centre(cx, cy, cz);
  for (uint32_t k = 0; k < m.vertexCount; ++k)
    EXPECT_NEAR(glm::length(worldVertex(m, k) - centre), r, 1e-5) << k;
  // The documented bound: every point of the surface is within r*(1-cos(pi/2Q)cos(pi/S)).
  const double sagitta = r * (1 - std::cos(kPi / (2 * rings)) * std::cos(kPi / segments));
  double deepest = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    glm::dvec3 a = worldVertex(m, m.indices[3 * t]), b = worldVertex(m, m.indices[3 * t + 1]),
               c = worldVertex(m, m.indices[3 * t + 2]);
    for (glm::dvec3 p : {(a + b + c) / 3.0, (a + b) / 2.0, (b + c) / 2.0, (a + c) / 2.0})
      deepest = std::max(deepest, r - glm::length(p - centre));
  }
  EXPECT_LE(deepest, sagitta + 1e-5);
  EXPECT_GT(deepest, 0.5 * sagitta);  // the bound is close, not loose
  expectOutward(m, centre, "sphere");
  expectWatertight(m);
}

TEST(Procedural, CubeIsClosedAndOutward) {
  LoadOptions world;
  world.placement = Placement::WorldSpace;
  Mesh m = loadMesh("procedural:cube?size=2", world);
  EXPECT_EQ(m.vertexCount, 8u);
  EXPECT_EQ(m.triangleCount(), 12u);
  std::set<std::tuple<float, float, float>> corners;
  for (uint32_t k = 0; k < 8; ++k) {
    glm::vec3 v = m.vertex(k);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(std::fabs(v[i]), 1.0f);
    corners.insert({v.x, v.y, v.z});
  }
  EXPECT_EQ(corners.size(), 8u);
  expectOutward(m, glm::dvec3(0), "cube");
  expectWatertight(m);
}

TEST(Procedural, CitySceneExtent) {
  LoadOptions world;
  world.placement = Placement::WorldSpace;
  Mesh m = loadMesh("procedural:city", world);
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  EXPECT_EQ(lo.y, 0.0f);
  EXPECT_GT(hi.y, 5.0f);
  EXPECT_NEAR(hi.x - lo.x, 22.0f, 1e-4f);
  EXPECT_GT(m.triangleCount(), 300u);
  EXPECT_EQ(m.stats.degenerateTriangles, 0u);
}

std::string errorOf(const std::string& spec) {
  try {
    loadMesh(spec);
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << spec << ": no error";
  return "";
}

TEST(Procedural, BadSpecsAreErrors) {
  std::string msg = errorOf("procedural:sphere?radius=1&colour=red");
  EXPECT_NE(msg.find("unknown key 'colour'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cx, cy, cz, radius, rings, segments"), std::string::npos) << msg;
  msg = errorOf("procedural:teapot");
  EXPECT_NE(msg.find("unknown procedural mesh 'teapot'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("spheres"), std::string::npos) << msg;
  msg = errorOf("procedural:spheres?tris=lots");
  EXPECT_NE(msg.find("not a number: 'lots'"), std::string::npos) << msg;
  msg = errorOf("procedural:sphere?segments=2");
  EXPECT_NE(msg.find("segments=2"), std::string::npos) << msg;
  msg = errorOf("procedural:city?size=3");
  EXPECT_NE(msg.find("known keys: none"), std::string::npos) << msg;
}

}  // namespace
}  // namespace aperture
