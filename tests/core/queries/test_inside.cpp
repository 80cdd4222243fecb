// Inside or outside (core/queries/inside.h): closedness counts on built meshes, parity with
// zero errors on closed meshes at points chosen to put rays through edges and vertices (the
// cube analytically, the sphere and the hole-filled bunny by the exact winding number), a
// naive parity that does make errors on the same points, the automatic choice, and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/queries/inside.h"
#include "core/queries/trace.h"
#include "core/queries/winding_number.h"
#include "core/queries/world_triangles.h"
#include "core/util/error.h"
#include "tests/inside_support.h"
#include "tests/support.h"

namespace aperture {
namespace inside_test {

using namespace test::inside;

// ---------------------------------------------------------------------------------------------
// checkClosed

TEST(CheckClosed, ClosedMeshesAreClosedWithThreeHalvesEdgesPerTriangle) {
  for (const std::string spec :
       {"procedural:cube?size=2", "procedural:sphere?segments=24&rings=12"}) {
    const Loaded s = sceneOf(loadMesh(spec));
    const ClosedCheck c = checkClosed(*s.scene);
    EXPECT_TRUE(c.closed) << spec;
    EXPECT_EQ(c.edges, 3 * s.mesh->triangleCount() / 2) << spec;
    EXPECT_EQ(c.boundaryEdges + c.nonManifoldEdges + c.misorientedEdges, 0u) << spec;
  }
  // Sides with vertices of their own join by position.
  const Loaded box = sceneOf(subdividedBox(4, false));
  const ClosedCheck c = checkClosed(*box.scene);
  EXPECT_TRUE(c.closed);
  EXPECT_EQ(c.edges, 3 * box.mesh->triangleCount() / 2);
}

TEST(CheckClosed, BoxWithoutTopHasItsRimAsBoundary) {
  const Loaded box = sceneOf(subdividedBox(4, true));
  const ClosedCheck c = checkClosed(*box.scene);
  EXPECT_FALSE(c.closed);
  EXPECT_EQ(c.boundaryEdges, 16u);  // 4 sides x 4 segments of the rim
  EXPECT_EQ(c.nonManifoldEdges + c.misorientedEdges, 0u);
  // Each triangle has 3 edges; the rim's are used once, all others twice.
  EXPECT_EQ(2 * c.edges - c.boundaryEdges, 3 * box.mesh->triangleCount());
}

TEST(CheckClosed, FlippedTriangleIsMisorientedOnItsThreeEdges) {
  Mesh m = subdividedBox(2, false);
  std::swap(m.indices[3 * 5 + 1], m.indices[3 * 5 + 2]);
  const Loaded s = sceneOf(std::move(m));
  const ClosedCheck c = checkClosed(*s.scene);
  EXPECT_FALSE(c.closed);
  EXPECT_EQ(c.misorientedEdges, 3u);
  EXPECT_EQ(c.boundaryEdges + c.nonManifoldEdges, 0u);
}

TEST(CheckClosed, ThreeTrianglesOnOneEdgeAreNonManifold) {
  MeshBuilder b;
  const uint32_t a = b.vertex({0, 0, 0}), e = b.vertex({1, 0, 0});
  b.triangle(a, e, b.vertex({0, 1, 0}));
  b.triangle(e, a, b.vertex({0, -1, 0}));
  b.triangle(a, e, b.vertex({0, 0, 1}));
  const Loaded s = sceneOf(b.mesh());
  const ClosedCheck c = checkClosed(*s.scene);
  EXPECT_FALSE(c.closed);
  EXPECT_EQ(c.nonManifoldEdges, 1u);
  EXPECT_EQ(c.boundaryEdges, 6u);
}

// ---------------------------------------------------------------------------------------------
// Points that put rays through edges and vertices

/// The grid over [-1.5, 1.5]³ in steps of 0.25: on the cube [-1, 1]³'s faces' planes, on lines
/// through its edges and vertices (along the axes and the faces' diagonals).
std::vector<double> cubeGrid() { return gridPoints(-1.5, 1.5, 13); }

/// Points from which parity direction `k` runs exactly through the given targets (vertices,
/// points on edges): target − s · size · direction for a few s, `size` the mesh's size.
std::vector<double> pointsAimedAt(const std::vector<glm::dvec3>& targets, int k, double size) {
  const glm::dvec3 d(parityDirection(k));
  std::vector<double> p;
  for (const glm::dvec3& t : targets)
    for (double s : {0.015 * size, 0.15 * size, 0.4 * size, 0.9 * size}) {
      const glm::dvec3 q = t - s * d;
      p.insert(p.end(), {q.x, q.y, q.z});
    }
  return p;
}

/// The cube's vertices, edge midpoints and face centres (where the diagonals cross) and
/// points a third along its edges and diagonals.
std::vector<glm::dvec3> cubeTargets() {
  std::vector<glm::dvec3> t;
  for (double x : {-1.0, -1.0 / 3, 0.0, 1.0 / 3, 1.0})
    for (double y : {-1.0, -1.0 / 3, 0.0, 1.0 / 3, 1.0})
      for (double z : {-1.0, 1.0}) {
        t.push_back({x, y, z}), t.push_back({z, x, y}), t.push_back({y, z, x});
      }
  return t;
}

/// Analytic inside of the cube [-1, 1]³: 1 inside, 0 outside, -1 on the surface.
int insideCube(const double* p) {
  const double m = std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2])});
  return m < 1 ? 1 : m > 1 ? 0 : -1;
}

/// A naive parity: one ray along `dir` from the point, re-traced from the next float past
/// each hit, every hit counted (traceRays, no care for edges, vertices or grazing rays).
std::vector<uint8_t> naiveParity(const Scene& scene, const std::vector<double>& points,
                                 glm::vec3 dir) {
  const size_t n = points.size() / 3;
  std::vector<TraceRay> rays(n);
  for (size_t i = 0; i < n; ++i) {
    rays[i].org = glm::vec3(glm::dvec3(points[3 * i], points[3 * i + 1], points[3 * i + 2]) -
                            scene.renderOrigin());
    rays[i].dir = dir;
  }
  std::vector<int> crossings(n, 0);
  std::vector<size_t> live(n);
  for (size_t i = 0; i < n; ++i) live[i] = i;
  while (!live.empty()) {
    std::vector<TraceRay> batch;
    for (size_t i : live) batch.push_back(rays[i]);
    const std::vector<TraceHit> hits = traceRays(scene, batch, 8);
    std::vector<size_t> next;
    for (size_t k = 0; k < live.size(); ++k)
      if (hits[k].hit() && crossings[live[k]] < 1000) {
        ++crossings[live[k]];
        rays[live[k]].tnear = std::nextafter(hits[k].t, INFINITY);
        next.push_back(live[k]);
      }
    live.swap(next);
  }
  std::vector<uint8_t> inside(n);
  for (size_t i = 0; i < n; ++i) inside[i] = uint8_t(crossings[i] & 1);
  return inside;
}

struct Errors {
  size_t tested = 0, errors = 0;
};

/// Errors of `inside` against `truth` (1, 0, or -1: on the surface, not counted).
Errors errorsAgainst(const std::vector<uint8_t>& inside, const std::vector<int>& truth) {
  Errors e;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (truth[i] < 0) continue;
    ++e.tested;
    e.errors += inside[i] != truth[i];
  }
  return e;
}

std::vector<int> cubeTruth(const std::vector<double>& points) {
  std::vector<int> t(points.size() / 3);
  for (size_t i = 0; i < t.size(); ++i) t[i] = insideCube(&points[3 * i]);
  return t;
}

/// Parity's truth from the exact winding number: odd = inside; -1 where the point is on the
/// surface (the sum is not within 1e-6 of an integer).
std::vector<int> windingTruth(const Mesh& mesh, const std::vector<double>& points) {
  const std::vector<glm::dvec3> corners = cornersOf(mesh);
  std::vector<int> t(points.size() / 3);
  for (size_t i = 0; i < t.size(); ++i) {
    const double w =
        exactWindingNumber(corners, {points[3 * i], points[3 * i + 1], points[3 * i + 2]});
    const double r = std::round(w);
    t[i] = std::abs(w - r) > 1e-6 ? -1 : int(std::abs(long(r)) & 1);
  }
  return t;
}

std::vector<double> joined(std::vector<double> a, const std::vector<double>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

TEST(InsideParity, CubeHasNoErrorsWhereNaiveParityHasSome) {
  const Loaded cube = sceneOf(loadMesh("procedural:cube?size=2"));
  const std::vector<double> points = joined(cubeGrid(), pointsAimedAt(cubeTargets(), 0, 2.0));
  const std::vector<int> truth = cubeTruth(points);
  for (int directions : {1, 5}) {
    InsideOptions o;
    o.method = InsideMethod::Parity;
    o.parityDirections = directions;
    const InsideResult r = insideOf(*cube.scene, points.data(), points.size() / 3, o);
    EXPECT_EQ(r.method, InsideMethod::Parity);
    const Errors e = errorsAgainst(r.inside, truth);
    EXPECT_EQ(e.errors, 0u) << directions << " directions, of " << e.tested;
    EXPECT_GT(e.tested, 2000u);
    EXPECT_GT(r.discardedRays, 0u);  // the aimed points met edges and vertices
    // Points on the surface: every ray starts on it.
    EXPECT_EQ(r.undecided, size_t(std::count(truth.begin(), truth.end(), -1)));
  }
  // Along an axis through the grid's edges and vertices, and along direction 0 through the
  // aimed-at edges and vertices, counting every hit goes wrong.
  const Errors axis = errorsAgainst(naiveParity(*cube.scene, points, {1, 0, 0}), truth);
  const Errors aimed = errorsAgainst(naiveParity(*cube.scene, points, parityDirection(0)), truth);
  std::printf("naive parity on the cube: %zu errors along +x, %zu along direction 0, of %zu\n",
              axis.errors, aimed.errors, axis.tested);
  EXPECT_GT(axis.errors + aimed.errors, 0u);
}

TEST(InsideParity, SphereHasNoErrorsThroughPolesAndVertices) {
  const Loaded sphere = sceneOf(loadMesh("procedural:sphere?segments=32&rings=16"));
  std::vector<glm::dvec3> targets;
  for (size_t v = 0; v < sphere.mesh->vertexCount; v += 7)
    targets.push_back(sphere.mesh->anchor + glm::dvec3(sphere.mesh->vertex(v)));
  std::vector<double> points = joined(gridPoints(-1.25, 1.25, 11), pointsAimedAt(targets, 0, 2.0));
  // On the pole axis (y), where axis rays run through the poles' fans.
  for (int k = -10; k <= 10; ++k) points.insert(points.end(), {0.0, k * 0.13, 0.0});
  const std::vector<int> truth = windingTruth(*sphere.mesh, points);
  InsideOptions o;
  o.method = InsideMethod::Parity;
  for (int directions : {1, 3}) {
    o.parityDirections = directions;
    const InsideResult r = insideOf(*sphere.scene, points.data(), points.size() / 3, o);
    const Errors e = errorsAgainst(r.inside, truth);
    EXPECT_EQ(e.errors, 0u) << directions << " directions, of " << e.tested;
    EXPECT_GT(r.discardedRays, 0u);
  }
  const Errors axis = errorsAgainst(naiveParity(*sphere.scene, points, {0, 1, 0}), truth);
  const Errors aimed = errorsAgainst(naiveParity(*sphere.scene, points, parityDirection(0)), truth);
  std::printf("naive parity on the sphere: %zu errors along +y, %zu along direction 0, of %zu\n",
              axis.errors, aimed.errors, axis.tested);
  EXPECT_GT(axis.errors + aimed.errors, 0u);
}

TEST(InsideParity, HoleFilledBunnyHasNoErrors) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const Loaded bunny = sceneOf(holesFilled(loadMesh(path)));
  const ClosedCheck closed = checkClosed(*bunny.scene);
  std::printf("filled bunny: %zu boundary, %zu non-manifold, %zu misoriented edges\n",
              closed.boundaryEdges, closed.nonManifoldEdges, closed.misorientedEdges);
  glm::vec3 lo, hi;
  bunny.mesh->bounds(lo, hi);
  const glm::dvec3 centre = bunny.mesh->anchor + glm::dvec3(lo + hi) * 0.5;
  const glm::dvec3 half = glm::dvec3(hi - lo) * 0.55;
  std::vector<double> points;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 600; ++i) {
    const glm::dvec3 p = centre + half * glm::dvec3(u(rng), u(rng), u(rng));
    points.insert(points.end(), {p.x, p.y, p.z});
  }
  // Aimed through vertices and edge midpoints along direction 0, and points in faces' planes
  // outside the faces (a + 1.6 (b − a) − 0.3 (c − a)).
  std::vector<glm::dvec3> targets;
  const Mesh& m = *bunny.mesh;
  for (size_t t = 0; t < m.triangleCount(); t += 173) {
    const glm::dvec3 a = m.anchor + glm::dvec3(m.vertex(m.indices[3 * t])),
                     b = m.anchor + glm::dvec3(m.vertex(m.indices[3 * t + 1])),
                     c = m.anchor + glm::dvec3(m.vertex(m.indices[3 * t + 2]));
    targets.push_back(a), targets.push_back(0.5 * (a + b));
    const glm::dvec3 inPlane = a + 1.6 * (b - a) - 0.3 * (c - a);
    points.insert(points.end(), {inPlane.x, inPlane.y, inPlane.z});
  }
  points = joined(points, pointsAimedAt(targets, 0, glm::length(glm::dvec3(hi - lo))));
  const std::vector<int> truth = windingTruth(m, points);
  InsideOptions o;
  o.method = InsideMethod::Parity;
  const InsideResult r = insideOf(*bunny.scene, points.data(), points.size() / 3, o);
  const Errors e = errorsAgainst(r.inside, truth);
  EXPECT_EQ(e.errors, 0u) << "of " << e.tested;
  o.parityDirections = 3;
  const InsideResult r3 = insideOf(*bunny.scene, points.data(), points.size() / 3, o);
  EXPECT_EQ(errorsAgainst(r3.inside, truth).errors, 0u);
  EXPECT_GT(e.tested, 3000u);
  const Errors aimed = errorsAgainst(naiveParity(*bunny.scene, points, parityDirection(0)), truth);
  std::printf("filled bunny: parity 0 errors of %zu; naive along direction 0: %zu errors\n",
              e.tested, aimed.errors);
}

TEST(InsideParity, InstancedCubesAreBothSolid) {
  const Mesh cube = loadMesh("procedural:cube?size=2");
  const glm::dvec3 offset(6.0, 1.0, -2.0);
  const Scene scene(test::numericsDevice(), test::placedTwice(cube, offset));
  ASSERT_GT(scene.instanceCount(), 0u);
  const std::vector<double> points = {0.1, 0.2, 0.3, offset.x + 0.2, offset.y, offset.z,
                                      3.0, 0.0, 0.0, offset.x + 1.9, offset.y, offset.z};
  InsideOptions o;
  o.method = InsideMethod::Parity;
  o.parityDirections = 3;
  const InsideResult r = insideOf(scene, points.data(), 4, o);
  EXPECT_EQ(r.inside, (std::vector<uint8_t>{1, 1, 0, 0}));
}

TEST(InsideParity, AnswersAreDeterministicOnTheSurfaceAndAlonePerPoint) {
  const Loaded cube = sceneOf(loadMesh("procedural:cube?size=2"));
  const std::vector<double> points = cubeGrid();  // 1/4 of them on the surface
  InsideOptions o;
  o.method = InsideMethod::Parity;
  const InsideResult all = insideOf(*cube.scene, points.data(), points.size() / 3, o);
  const InsideResult again = insideOf(*cube.scene, points.data(), points.size() / 3, o);
  EXPECT_EQ(all.inside, again.inside);
  for (size_t i = 0; i < points.size() / 3; i += 17) {
    const InsideResult one = insideOf(*cube.scene, &points[3 * i], 1, o);
    EXPECT_EQ(one.inside[0], all.inside[i]) << i;
  }
}

// ---------------------------------------------------------------------------------------------
// One traversal per ray (a scene built with BuildOptions::contextFilter) against the retrace

/// The scene's objects built again with the context filter: parity then collects every hit of
/// a ray in one traversal.
std::unique_ptr<Scene> filterTwin(const Scene& scene, BuildOptions options = {}) {
  options.contextFilter = true;
  return std::make_unique<Scene>(test::numericsDevice(), scene.objects(), options);
}

/// insideOf by the retrace (`scene`) and by one traversal (its filterTwin) agree bit for bit
/// on insides, discarded rays and undecided points.
void expectOneTraversalEqualsRetrace(const Scene& scene, const std::vector<double>& points,
                                     const char* what) {
  ASSERT_FALSE(scene.options().contextFilter);
  const std::unique_ptr<Scene> twin = filterTwin(scene, scene.options());
  for (int directions : {1, 3, 7}) {
    InsideOptions o;
    o.method = InsideMethod::Parity;
    o.parityDirections = directions;
    const InsideResult retrace = insideOf(scene, points.data(), points.size() / 3, o);
    const InsideResult filter = insideOf(*twin, points.data(), points.size() / 3, o);
    EXPECT_EQ(filter.inside, retrace.inside) << what << ", " << directions << " directions";
    EXPECT_EQ(filter.discardedRays, retrace.discardedRays) << what << ", " << directions;
    EXPECT_EQ(filter.undecided, retrace.undecided) << what << ", " << directions;
    EXPECT_GT(retrace.discardedRays, 0u) << what;  // the points do meet edges and vertices
  }
}

TEST(InsideParity, OneTraversalEqualsRetraceThroughEdgesAndVertices) {
  const Loaded cube = sceneOf(loadMesh("procedural:cube?size=2"));
  std::vector<double> cubePoints = cubeGrid();
  for (int k : {0, 1, 2}) cubePoints = joined(cubePoints, pointsAimedAt(cubeTargets(), k, 2.0));
  expectOneTraversalEqualsRetrace(*cube.scene, cubePoints, "cube");

  const Loaded sphere = sceneOf(loadMesh("procedural:sphere?segments=32&rings=16"));
  std::vector<glm::dvec3> targets;
  for (size_t v = 0; v < sphere.mesh->vertexCount; ++v)
    targets.push_back(sphere.mesh->anchor + glm::dvec3(sphere.mesh->vertex(v)));
  std::vector<double> spherePoints = gridPoints(-1.25, 1.25, 11);
  for (int k : {0, 1, 2}) spherePoints = joined(spherePoints, pointsAimedAt(targets, k, 2.0));
  for (int k = -10; k <= 10; ++k) spherePoints.insert(spherePoints.end(), {0.0, k * 0.13, 0.0});
  expectOneTraversalEqualsRetrace(*sphere.scene, spherePoints, "sphere");
}

TEST(InsideParity, OneTraversalEqualsRetraceOnChunksAndInstances) {
  const Mesh sphere = loadMesh("procedural:sphere?segments=64&rings=48");
  BuildOptions chunks;
  chunks.bvhChunkTriangles = 1024;
  chunks.maxChunksPerCell = INFINITY;
  const Scene chunked(test::numericsDevice(), std::vector<const Mesh*>{&sphere}, chunks);
  ASSERT_GT(chunked.stats().chunks, 1u);
  std::vector<glm::dvec3> targets;
  for (size_t v = 0; v < sphere.vertexCount; v += 5)
    targets.push_back(sphere.anchor + glm::dvec3(sphere.vertex(v)));
  const std::vector<double> points =
      joined(gridPoints(-1.25, 1.25, 9), pointsAimedAt(targets, 0, 2.0));
  expectOneTraversalEqualsRetrace(chunked, points, "chunked sphere");

  const Mesh cube = loadMesh("procedural:cube?size=2");
  const glm::dvec3 offset(6.0, 1.0, -2.0);
  const Scene twice(test::numericsDevice(), test::placedTwice(cube, offset));
  ASSERT_GT(twice.instanceCount(), 0u);
  std::vector<double> both = joined(cubeGrid(), pointsAimedAt(cubeTargets(), 0, 2.0));
  const size_t n = both.size() / 3;
  for (size_t i = 0; i < n; ++i)
    both.insert(both.end(),
                {both[3 * i] + offset.x, both[3 * i + 1] + offset.y, both[3 * i + 2] + offset.z});
  expectOneTraversalEqualsRetrace(twice, both, "instanced cubes");
}

// ---------------------------------------------------------------------------------------------
// The automatic choice, winding, bad input

TEST(InsideOf, AutomaticIsParityWhenClosedAndWindingWhenOpen) {
  const Loaded closed = sceneOf(subdividedBox(8, false));
  const Loaded open = sceneOf(subdividedBox(8, true));
  const std::vector<double> points = gridPoints(-1.3, 1.3, 9);
  const InsideResult a = insideOf(*closed.scene, points.data(), points.size() / 3);
  EXPECT_EQ(a.method, InsideMethod::Parity);
  EXPECT_TRUE(a.winding.empty());
  EXPECT_EQ(errorsAgainst(a.inside, cubeTruth(points)).errors, 0u);
  const InsideResult b = insideOf(*open.scene, points.data(), points.size() / 3);
  EXPECT_EQ(b.method, InsideMethod::Winding);
  ASSERT_EQ(b.winding.size(), points.size() / 3);
  const std::vector<glm::dvec3> corners = cornersOf(*open.mesh);
  for (size_t i = 0; i < b.winding.size(); ++i) {
    const double exact =
        exactWindingNumber(corners, {points[3 * i], points[3 * i + 1], points[3 * i + 2]});
    EXPECT_LE(std::abs(b.winding[i] - exact), b.windingErrorBound[i] + 1e-10) << i;
    if (std::abs(exact - 0.5) > 0.01) {
      EXPECT_EQ(b.inside[i], exact > 0.5 ? 1 : 0) << i;
    }
  }
}

TEST(InsideOf, KeptClosedCheckAndTreeAreUsed) {
  const Loaded open = sceneOf(subdividedBox(8, true));
  const std::vector<double> points = gridPoints(-1.3, 1.3, 7);
  // A closedness the caller claims is taken as given: parity runs on the open box.
  ClosedCheck claimed;
  claimed.closed = true;
  InsideOptions o;
  o.closed = &claimed;
  EXPECT_EQ(insideOf(*open.scene, points.data(), points.size() / 3, o).method,
            InsideMethod::Parity);
  // A kept tree gives what a tree built per call gives.
  const WindingNumberTree tree(worldTriangleCorners(*open.scene));
  InsideOptions w;
  w.method = InsideMethod::Winding;
  const InsideResult fresh = insideOf(*open.scene, points.data(), points.size() / 3, w);
  w.windingTree = &tree;
  const InsideResult kept = insideOf(*open.scene, points.data(), points.size() / 3, w);
  EXPECT_EQ(kept.winding, fresh.winding);
  EXPECT_EQ(kept.inside, fresh.inside);
}

TEST(InsideOf, NonFinitePointsAreOutsideAndCounted) {
  const Loaded cube = sceneOf(loadMesh("procedural:cube?size=2"));
  const double nan = std::nan(""), inf = INFINITY;
  const std::vector<double> points = {0, 0, 0, nan, 0, 0, 0, inf, 0, 0.5, 0.5, 0.5};
  for (InsideMethod m : {InsideMethod::Parity, InsideMethod::Winding}) {
    InsideOptions o;
    o.method = m;
    const InsideResult r = insideOf(*cube.scene, points.data(), 4, o);
    EXPECT_EQ(r.inside, (std::vector<uint8_t>{1, 0, 0, 1})) << insideMethodName(m);
    EXPECT_EQ(r.nonFinite, 2u) << insideMethodName(m);
    if (m == InsideMethod::Winding) {
      EXPECT_TRUE(std::isnan(r.winding[1]));
      EXPECT_TRUE(std::isnan(r.winding[2]));
      EXPECT_NEAR(r.winding[0], 1.0, 1e-12);
    }
  }
}

TEST(InsideOf, BadOptionsAndNamesAreErrors) {
  const Loaded cube = sceneOf(loadMesh("procedural:cube?size=2"));
  const double p[3] = {0, 0, 0};
  for (int directions : {0, 2, 17}) {
    InsideOptions o;
    o.parityDirections = directions;
    EXPECT_NE(test::errorOf([&] { insideOf(*cube.scene, p, 1, o); }).find("parityDirections"),
              std::string::npos);
  }
  InsideOptions o;
  o.windingBeta = 0.5;
  EXPECT_NE(test::errorOf([&] { insideOf(*cube.scene, p, 1, o); }).find("windingBeta"),
            std::string::npos);
  EXPECT_NE(test::errorOf([] { parseInsideMethod("windng"); }).find("did you mean"),
            std::string::npos);
  EXPECT_EQ(parseInsideMethod("parity"), InsideMethod::Parity);
  EXPECT_NE(test::errorOf([] { parityDirection(kParityDirectionCount); }), "");
}

TEST(InsideOf, ParityDirectionsAreUnitAndOffTheAxes) {
  for (int k = 0; k < kParityDirectionCount; ++k) {
    const glm::vec3 d = parityDirection(k);
    EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
    EXPECT_GT(std::min({std::abs(d.x), std::abs(d.y), std::abs(d.z)}), 1e-3f) << k;
  }
}

}  // namespace inside_test
}  // namespace aperture
