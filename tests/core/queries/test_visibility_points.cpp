// Point visibility (core/queries/visibility.h): a brute-force double-precision occlusion check
// of points, the relative tolerance towards the camera, and the transposed rows and observation
// counts of hand-made examples.
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
namespace visibility_points_test {

using namespace test::visibility;

namespace {

/// A closed UV sphere of radius r at c (seg longitudes, rings latitudes), outward winding.
void addSphere(MeshBuilder& b, double r, const glm::dvec3& c, int seg, int rings) {
  const double pi = 3.14159265358979323846;
  auto at = [&](int i, int j) {
    const double th = pi * i / rings, ph = 2 * pi * j / seg;
    return c +
           r * glm::dvec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
  };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < seg; ++j) {
      const glm::dvec3 a = at(i, j), bb = at(i, j + 1), cc = at(i + 1, j), d = at(i + 1, j + 1);
      if (i > 0) b.triangle(a, bb, cc);
      if (i + 1 < rings) b.triangle(bb, d, cc);
    }
}

/// Möller–Trumbore in double: the ray o + t·dir's parameter t > 0 at the triangle's plane and
/// the smallest barycentric coordinate there (negative: outside the triangle), or nothing for
/// a ray parallel to the plane.
struct MtHit {
  double t, minBary;
};
std::optional<MtHit> mollerTrumbore(const glm::dvec3& o, const glm::dvec3& dir,
                                    const Corners& tri) {
  const glm::dvec3 e1 = tri.b - tri.a, e2 = tri.c - tri.a;
  const glm::dvec3 pv = glm::cross(dir, e2);
  const double det = glm::dot(e1, pv);
  if (std::abs(det) < 1e-300) return std::nullopt;
  const glm::dvec3 tv = o - tri.a;
  const double u = glm::dot(tv, pv) / det;
  const glm::dvec3 qv = glm::cross(tv, e1);
  const double v = glm::dot(dir, qv) / det;
  const double t = glm::dot(e2, qv) / det;
  if (!(t > 0)) return std::nullopt;
  return MtHit{t, std::min({u, v, 1 - u - v})};
}

enum class Brute { Seen, Occluded, Outside, Ambiguous };

/// The brute-force answer for point p in pinhole `pin`: the ray from the eye towards p, every
/// triangle tested in double. Ambiguous (excluded from the comparison): the projection lies
/// within 1e-6 px of the image's edge; an occluder's distance lies within 1e-5·d of the limit
/// d·(1 − tol); or a triangle is met within 1e-6 (barycentric) of its edges before the limit
/// (a ray grazing an edge, which float rounding may move to either side).
Brute bruteForce(const Mesh& mesh, const Pinhole& pin, const glm::dvec3& p, double tol) {
  const std::optional<glm::dvec2> r = pin.raster(p);
  if (!r || !pin.inside(*r)) {
    const bool nearEdge = r && (std::abs(r->x) < 1e-6 || std::abs(r->x - pin.width) < 1e-6 ||
                                std::abs(r->y) < 1e-6 || std::abs(r->y - pin.height) < 1e-6);
    return nearEdge ? Brute::Ambiguous : Brute::Outside;
  }
  if (std::min({r->x, r->y, pin.width - r->x, pin.height - r->y}) < 1e-6) return Brute::Ambiguous;
  const double d = glm::length(p - pin.eye);
  const glm::dvec3 dir = (p - pin.eye) / d;
  const double limit = d * (1 - tol), band = 1e-5 * d, edge = 1e-6;
  bool ambiguous = false, occluded = false;
  for (size_t f = 0; f < mesh.triangleCount(); ++f) {
    const std::optional<MtHit> h = mollerTrumbore(pin.eye, dir, cornersOf(mesh, f));
    if (!h || h->minBary < -edge || h->t > limit + band) continue;
    if (h->minBary <= edge || h->t >= limit - band)
      ambiguous = true;
    else
      occluded = true;
  }
  if (occluded) return Brute::Occluded;
  return ambiguous ? Brute::Ambiguous : Brute::Seen;
}

/// A closed sphere (radius 0.5) and a plate in front of it, away from the origin so the render
/// origin (the anchor) matters.
Mesh sphereAndPlate(const glm::dvec3& anchor) {
  MeshBuilder b;
  addSphere(b, 0.5, anchor, 24, 12);
  const glm::dvec3 o = anchor + glm::dvec3(0.1, -0.1, 0.8);
  b.quad(o + glm::dvec3(-0.3, -0.2, 0), o + glm::dvec3(0.25, -0.2, 0),
         o + glm::dvec3(0.25, 0.15, 0), o + glm::dvec3(-0.3, 0.15, 0));
  return b.mesh(anchor);
}

}  // namespace

TEST(Visibility, PointsAgreeWithBruteForceInDouble) {
  const glm::dvec3 centre(10, -4, 3);
  const Loaded scene = sceneOf(sphereAndPlate(centre));
  const std::vector<CameraParams> params = {
      perspective(centre + glm::dvec3(0.2, 0.3, 3), centre, {0, 1, 0}, 64, 48, 30),
      perspective(centre + glm::dvec3(-2.5, 0.5, 1.5), centre, {0, 1, 0}, 40, 40, 45),
      perspective(centre + glm::dvec3(0.5, -2, -2), centre + glm::dvec3(0.2, 0, 0), {0, 1, 0}, 50,
                  30, 35)};
  const Cameras cams(*scene.scene, params);

  // Points in a box around the sphere (in front of, behind and inside the surface) and on it
  // (random barycentric points of random triangles).
  std::mt19937 rng(15);
  std::uniform_real_distribution<double> box(-1.0, 1.0), unit(0.0, 1.0);
  std::vector<glm::dvec3> points;
  constexpr size_t kBoxPoints = 5000;  // with the surface points, more than one task of 4096
  for (size_t k = 0; k < kBoxPoints; ++k)
    points.push_back(centre + glm::dvec3(box(rng), box(rng), box(rng)));
  const Mesh& mesh = *scene.mesh;
  for (int k = 0; k < 500; ++k) {
    const Corners t = cornersOf(mesh, size_t(rng() % mesh.triangleCount()));
    double u = unit(rng), v = unit(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    points.push_back(t.a + u * (t.b - t.a) + v * (t.c - t.a));
  }

  for (double tol : {0.01, 0.0, 0.2}) {
    SCOPED_TRACE(tol);
    PointVisibilityOptions o;
    o.tolerance = tol;
    const PointVisibility v = pointVisibility(*scene.scene, cams.list, points, o);
    ASSERT_EQ(v.pointCameras.rows(), points.size());
    ASSERT_EQ(v.cameraPoints.rows(), params.size());
    size_t compared = 0, excluded = 0, excludedInBox = 0, seen = 0, occluded = 0, outside = 0,
           wrong = 0;
    for (size_t c = 0; c < params.size(); ++c) {
      const Pinhole pin(params[c]);
      std::vector<char> listed(points.size(), 0);
      for (uint32_t k : row(v.cameraPoints, c)) listed[k] = 1;
      for (size_t k = 0; k < points.size(); ++k) {
        const Brute want = bruteForce(mesh, pin, points[k], tol);
        if (want == Brute::Ambiguous) {
          ++excluded;
          excludedInBox += k < kBoxPoints;
          continue;
        }
        ++compared;
        seen += want == Brute::Seen, occluded += want == Brute::Occluded;
        outside += want == Brute::Outside;
        if ((want == Brute::Seen) != bool(listed[k])) {
          ++wrong;
          ADD_FAILURE() << "camera " << c << " point " << k << ": brute force says "
                        << (want == Brute::Seen ? "seen" : "not seen");
          if (wrong > 10) return;
        }
      }
    }
    // Points on the surface lie in the band when tol = 0 (their own triangle is met at d):
    // only the box points must nearly all be compared.
    EXPECT_LT(excludedInBox, kBoxPoints * params.size() / 50) << "too many points in the bands";
    EXPECT_GT(compared, points.size());
    EXPECT_GT(seen, 500u);
    EXPECT_GT(occluded, 500u);
    EXPECT_GT(outside, 100u);
  }
}

// The tolerance is relative to the point's distance d and measured towards the camera. Camera
// at distance 5 from a wall (the plane z = 0): a point 0.01 in front is seen, 0.1 behind (past
// 1 % of d = 0.051) occluded; a point on the wall is seen with tol = 0.01. A point 0.03
// behind (within 1 %, so seen with tol = 0.01) is occluded with tol = 0, and would be
// occluded too if the tolerance were an absolute 0.01 (limit d − 0.01 = 5.02 > 5).
TEST(Visibility, PointToleranceIsRelativeAndTowardsTheCamera) {
  MeshBuilder b;
  b.quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0});
  const Loaded wall = sceneOf(b.mesh());
  const Cameras cams(*wall.scene, {perspective({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 32, 32, 40)});
  const std::vector<glm::dvec3> points = {
      {0.1, 0.15, 0.01}, {0.1, 0.15, -0.1}, {0.1, 0.15, 0.0}, {0.1, 0.15, -0.03}};
  auto seenWith = [&](double tol) {
    PointVisibilityOptions o;
    o.tolerance = tol;
    return row(pointVisibility(*wall.scene, cams.list, points, o).cameraPoints, 0);
  };
  EXPECT_EQ(seenWith(0.01), (std::vector<uint32_t>{0, 2, 3}));
  // With tol = 0 the point on the wall (index 2) meets the wall at t = d up to rounding, either
  // side of the limit: only the others are checked.
  const std::vector<uint32_t> exact = seenWith(0.0);
  auto holds = [&](uint32_t k) { return std::find(exact.begin(), exact.end(), k) != exact.end(); };
  EXPECT_TRUE(holds(0));
  EXPECT_FALSE(holds(1));
  EXPECT_FALSE(holds(3));
}

TEST(Visibility, TransposeRowsOfAHandMadeExample) {
  SparseRows r;
  r.indptr = {0, 2, 2, 4, 5};  // rows {1, 3}, {}, {0, 1}, {3}
  r.indices = {1, 3, 0, 1, 3};
  const SparseRows t = transposeRows(r, 5);
  EXPECT_EQ(t.indptr, (std::vector<uint64_t>{0, 1, 3, 3, 5, 5}));
  EXPECT_EQ(test::asVector(t.indices), (std::vector<uint32_t>{2, 0, 2, 0, 3}));
  const std::string e = test::errorOf([&] { transposeRows(r, 3); });
  EXPECT_NE(e.find("index 3"), std::string::npos) << e;
}

// A wall (z = 0, |x|, |y| <= 1) between camera 0 at z = 5 and camera 1 at z = −5, both looking
// at the origin with a 60° field. p0 = (0, 0, 1): in front of the wall for camera 0, behind it
// for camera 1. p1 = (0, 0, −1): the reverse. p2 = (0, 0, 6): behind camera 0 (outside), and
// behind the wall for camera 1. p3 = (10, 0, 0): x / depth = 2 > tan 30°, outside camera 0.
// Observations (point, camera): (0,0) seen, (0,1) occluded, (1,0) occluded, (1,1) seen,
// (2,0) outside, (2,1) occluded, (3,0) outside: 2 seen, 3 occluded, 2 outside.
TEST(Visibility, ClassifyObservationsCountsAHandMadeScene) {
  MeshBuilder b;
  b.quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0});
  const Loaded wall = sceneOf(b.mesh());
  const Cameras cams(*wall.scene, {perspective({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 32, 32, 60),
                                   perspective({0, 0, -5}, {0, 0, 0}, {0, 1, 0}, 32, 32, 60)});
  const std::vector<glm::dvec3> points = {{0, 0, 1}, {0, 0, -1}, {0, 0, 6}, {10, 0, 0}};
  const std::vector<PointObservation> obs = {{0, 0}, {0, 1}, {1, 0}, {1, 1},
                                             {2, 0}, {2, 1}, {3, 0}};
  const ObservationCounts n = classifyObservations(*wall.scene, cams.list, points, obs, 0.01);
  EXPECT_EQ(n.seen, 2u);
  EXPECT_EQ(n.occluded, 3u);
  EXPECT_EQ(n.outside, 2u);
  // The same decision as pointVisibility.
  const PointVisibility v = pointVisibility(*wall.scene, cams.list, points);
  EXPECT_EQ(row(v.pointCameras, 0), std::vector<uint32_t>{0});
  EXPECT_EQ(row(v.pointCameras, 1), std::vector<uint32_t>{1});
  EXPECT_EQ(row(v.pointCameras, 2), std::vector<uint32_t>{});
  EXPECT_EQ(row(v.pointCameras, 3), std::vector<uint32_t>{});
  const std::string e = test::errorOf([&] {
    classifyObservations(*wall.scene, cams.list, points, {{0, 2}}, 0.01);
  });
  EXPECT_NE(e.find("observation 0"), std::string::npos) << e;
}

}  // namespace visibility_points_test
}  // namespace aperture
