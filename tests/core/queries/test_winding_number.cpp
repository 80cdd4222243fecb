// The generalized winding number (core/queries/winding_number.h): solid angles in closed form,
// the exact sum on closed meshes, and the tree against the exact sum within its error bound
// on open meshes (a box without its top, the bunny as scanned).
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/queries/winding_number.h"
#include "core/queries/world_triangles.h"
#include "core/util/error.h"
#include "tests/inside_support.h"
#include "tests/support.h"

namespace aperture {
namespace winding_test {

using namespace test::inside;

constexpr double kPi = 3.14159265358979323846;

TEST(WindingNumber, SolidAngleOfAnOctantTriangleIsAnEighthOfTheSphere) {
  const glm::dvec3 a(1, 0, 0), b(0, 1, 0), c(0, 0, 1), origin(0.0);
  // Normal (b − a) × (c − a) = (1, 1, 1) points away from the origin: the origin is behind.
  EXPECT_NEAR(triangleSolidAngle(a, b, c, origin), kPi / 2, 1e-14);
  EXPECT_NEAR(triangleSolidAngle(a, c, b, origin), -kPi / 2, 1e-14);
  // Seen from far along the normal, Ω → area · cos / distance² (area √3/2, distance ~ L√3).
  const double L = 1e4;
  const glm::dvec3 far(-L, -L, -L);
  const double distance = std::sqrt(3.0) * (L + 1.0 / 3.0);
  EXPECT_NEAR(triangleSolidAngle(a, b, c, far), std::sqrt(3.0) / 2 / (distance * distance), 1e-12);
  EXPECT_EQ(triangleSolidAngle(a, b, c, a), 0.0);
}

TEST(WindingNumber, ExactSumIsOneInsideAndZeroOutsideClosedMeshes) {
  for (const bool sphere : {false, true}) {
    const Mesh m =
        sphere ? loadMesh("procedural:sphere?segments=24&rings=12") : subdividedBox(3, false);
    const std::vector<glm::dvec3> corners = cornersOf(m);
    SCOPED_TRACE(m.name);
    EXPECT_NEAR(exactWindingNumber(corners, glm::dvec3(0.1, -0.2, 0.3)), 1.0, 1e-12);
    EXPECT_NEAR(exactWindingNumber(corners, glm::dvec3(1.7, 0.4, -0.3)), 0.0, 1e-12);
    EXPECT_NEAR(exactWindingNumber(corners, glm::dvec3(0.0, 0.0, -5.0)), 0.0, 1e-12);
  }
}

TEST(WindingNumber, OpenBoxWithoutTopIsHalfwayAtItsMissingTop) {
  // By symmetry, the centre of the missing top sees the five sides as half the sphere.
  const std::vector<glm::dvec3> corners = cornersOf(subdividedBox(2, true));
  EXPECT_NEAR(exactWindingNumber(corners, glm::dvec3(0, 0, 1)), 0.5, 1e-12);
  // The centre of the box misses the top's solid angle, 4π/6.
  EXPECT_NEAR(exactWindingNumber(corners, glm::dvec3(0.0)), 5.0 / 6.0, 1e-12);
}

/// Compares the tree with the exact sum at `points`: every value within the tree's bound
/// (plus rounding), and the share of the points farther than `away` from the surface that the
/// tree classifies (w > 0.5) as the exact sum does.
struct TreeAgreement {
  size_t tested = 0, outsideBound = 0, away = 0, agreeing = 0;
  double worstError = 0, worstBound = 0, largestRatio = 0;
};
TreeAgreement compareTree(const std::vector<glm::dvec3>& corners,
                          const std::vector<glm::dvec3>& points, double beta, double away) {
  const WindingNumberTree tree(corners);
  TreeAgreement a;
  std::vector<double> flat;
  for (const glm::dvec3& p : points) flat.insert(flat.end(), {p.x, p.y, p.z});
  std::vector<double> w(points.size()), bound(points.size()), exact(points.size()),
      distance(points.size());
  tree.evaluate(flat.data(), points.size(), beta, w.data(), bound.data());
  tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
    exact[i] = exactWindingNumber(corners, points[i]);
    distance[i] = distanceToSoup(corners, points[i]);
  });
  for (size_t i = 0; i < points.size(); ++i) {
    const double error = std::abs(w[i] - exact[i]);
    ++a.tested;
    a.outsideBound += error > bound[i] + 1e-10;
    a.worstError = std::max(a.worstError, error);
    a.worstBound = std::max(a.worstBound, bound[i]);
    if (bound[i] > 0) a.largestRatio = std::max(a.largestRatio, error / bound[i]);
    if (distance[i] > away) {
      ++a.away;
      a.agreeing += (w[i] > 0.5) == (exact[i] > 0.5);
    }
  }
  return a;
}

std::vector<glm::dvec3> randomPoints(size_t n, glm::dvec3 lo, glm::dvec3 hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> points(n);
  for (glm::dvec3& p : points) p = lo + (hi - lo) * glm::dvec3(u(rng), u(rng), u(rng));
  return points;
}

TEST(WindingNumber, TreeOnOpenBoxIsWithinItsBoundAndAgreesWithTheExactSum) {
  const Mesh box = subdividedBox(16, true);  // 2560 triangles
  const std::vector<glm::dvec3> corners = cornersOf(box);
  ASSERT_GT(corners.size() / 3, kWindingExactBelow);
  std::vector<glm::dvec3> points = randomPoints(20000, glm::dvec3(-1.6), glm::dvec3(1.6), 7);
  // Points on the sides' planes and on lines through the grid's vertices.
  for (int k = -8; k <= 8; ++k) points.push_back(glm::dvec3(1.0, k / 8.0 * 1.5, 0.3));
  for (int k = -8; k <= 8; ++k) points.push_back(glm::dvec3(0.25, 0.5, k / 8.0 * 1.5));
  const TreeAgreement a = compareTree(corners, points, 2.0, 0.02);
  EXPECT_EQ(a.outsideBound, 0u) << "worst error " << a.worstError;
  EXPECT_GE(double(a.agreeing), 0.9999 * double(a.away)) << a.agreeing << " of " << a.away;
  EXPECT_GT(a.away, 15000u);
  EXPECT_GT(a.worstBound, 0.0);  // the far field was used
  std::printf(
      "open box: worst error %.3g, worst bound %.3g, largest error/bound %.3g, "
      "%zu of %zu points away from the surface agree\n",
      a.worstError, a.worstBound, a.largestRatio, a.agreeing, a.away);
}

TEST(WindingNumber, TreeBoundTightensWithBeta) {
  const std::vector<glm::dvec3> corners = cornersOf(subdividedBox(16, true));
  const std::vector<glm::dvec3> points = randomPoints(500, glm::dvec3(-3.0), glm::dvec3(3.0), 9);
  const TreeAgreement coarse = compareTree(corners, points, 1.5, 0.02);
  const TreeAgreement fine = compareTree(corners, points, 4.0, 0.02);
  EXPECT_EQ(coarse.outsideBound, 0u);
  EXPECT_EQ(fine.outsideBound, 0u);
  EXPECT_LT(fine.worstBound, coarse.worstBound);
  EXPECT_LT(fine.worstError, coarse.worstError);
}

TEST(WindingNumber, TreeOnTheScannedBunnyIsWithinItsBound) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const Mesh bunny = loadMesh(path);
  const std::vector<glm::dvec3> corners = cornersOf(bunny);
  glm::vec3 lo, hi;
  bunny.bounds(lo, hi);
  const glm::dvec3 centre = bunny.anchor + glm::dvec3(lo + hi) * 0.5;
  const glm::dvec3 half = glm::dvec3(hi - lo) * 0.6;
  const TreeAgreement a = compareTree(corners, randomPoints(1500, centre - half, centre + half, 11),
                                      2.0, 0.01 * glm::length(glm::dvec3(hi - lo)));
  EXPECT_EQ(a.outsideBound, 0u) << "worst error " << a.worstError;
  EXPECT_GE(double(a.agreeing), 0.9999 * double(a.away)) << a.agreeing << " of " << a.away;
  std::printf("bunny: worst error %.3g, worst bound %.3g, largest error/bound %.3g\n", a.worstError,
              a.worstBound, a.largestRatio);
}

TEST(WindingNumber, TreeOnTheLowResolutionBunnyAgreesOnManyPoints) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper_res4.ply");
  const Mesh bunny = loadMesh(path);
  const std::vector<glm::dvec3> corners = cornersOf(bunny);
  ASSERT_GT(corners.size() / 3, kWindingExactBelow);
  glm::vec3 lo, hi;
  bunny.bounds(lo, hi);
  const glm::dvec3 centre = bunny.anchor + glm::dvec3(lo + hi) * 0.5;
  const glm::dvec3 half = glm::dvec3(hi - lo) * 0.6;
  const TreeAgreement a =
      compareTree(corners, randomPoints(30000, centre - half, centre + half, 13), 2.0,
                  0.01 * glm::length(glm::dvec3(hi - lo)));
  EXPECT_EQ(a.outsideBound, 0u) << "worst error " << a.worstError;
  EXPECT_GE(double(a.agreeing), 0.9999 * double(a.away)) << a.agreeing << " of " << a.away;
  EXPECT_GT(a.away, 20000u);
  std::printf("low-resolution bunny: %zu of %zu points away from the surface agree\n", a.agreeing,
              a.away);
}

TEST(WindingNumber, FarFieldErrorFallsAsTheFifthPowerOfDistance) {
  // Far from the open box its whole tree is one far-field node: the terms kept up to the
  // third order leave an error of order R³/d⁵ (a term wrong at the second or third order
  // would leave R/d³ or R²/d⁴, falling 8 or 16 times per doubling instead of 32;
  // measured: 25.8, 29.3, 30.9 from d = 16).
  const std::vector<glm::dvec3> corners = cornersOf(subdividedBox(16, true));
  const WindingNumberTree tree(corners);
  const glm::dvec3 dir = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
  double previous = 0;
  for (double d : {16.0, 32.0, 64.0, 128.0}) {
    const glm::dvec3 p = d * dir;
    const WindingValue v = tree.evaluate(p, 2.0);
    const double error = std::abs(v.winding - exactWindingNumber(corners, p));
    EXPECT_LE(error, v.errorBound);
    if (previous > 0) {
      EXPECT_GT(previous / error, 20.0) << "at " << d;
    }
    previous = error;
  }
}

TEST(WindingNumber, SmallSoupsAreSummedExactly) {
  const std::vector<glm::dvec3> corners = cornersOf(subdividedBox(1, true));  // 10 triangles
  const WindingNumberTree tree(corners);
  EXPECT_EQ(tree.nodeCount(), 0u);
  const glm::dvec3 p(0.2, 0.1, 0.9);
  const WindingValue v = tree.evaluate(p, 2.0);
  EXPECT_EQ(v.winding, exactWindingNumber(corners, p));
  EXPECT_EQ(v.errorBound, 0.0);
}

TEST(WindingNumber, NonFinitePointsGiveNaNAndBadBetaIsAnError) {
  const WindingNumberTree tree(cornersOf(subdividedBox(8, false)));
  const double points[6] = {0.0, 0.0, 0.0, std::nan(""), 0.0, 0.0};
  double w[2], bound[2];
  tree.evaluate(points, 2, 2.0, w, bound);
  EXPECT_LE(std::abs(w[0] - 1.0), bound[0] + 1e-10);
  EXPECT_TRUE(std::isnan(w[1]));
  EXPECT_TRUE(std::isnan(bound[1]));
  EXPECT_NE(test::errorOf([&] { tree.evaluate(points, 2, 1.0, w, bound); }).find("beta 1"),
            std::string::npos);
}

TEST(WindingNumber, WorldCornersFollowThePlacement) {
  const Mesh box = subdividedBox(1, false);
  const glm::dvec3 offset(10.0, -3.0, 2.0);
  const std::vector<SceneObject> objects = test::placedTwice(box, offset);
  const Scene scene(test::numericsDevice(), objects);
  const std::vector<glm::dvec3> corners = worldTriangleCorners(scene);
  ASSERT_EQ(corners.size(), 2 * 3 * box.triangleCount());
  // The second placement is a rotation about the origin, then the offset: its centre is the
  // offset, and it is as closed there as the first one is at the origin.
  const std::vector<glm::dvec3> second(corners.begin() + long(corners.size() / 2), corners.end());
  EXPECT_NEAR(exactWindingNumber(second, offset), 1.0, 1e-9);
  EXPECT_NEAR(exactWindingNumber(second, glm::dvec3(0.0)), 0.0, 1e-9);
  EXPECT_NEAR(exactWindingNumber(corners, glm::dvec3(0.0)), 1.0, 1e-9);
}

TEST(WindingNumber, TreeKeepsTheExactSumOfTheSoup) {
  // The tree stores the corners in leaf order: its exact sum must still be the soup's.
  const std::vector<glm::dvec3> corners = cornersOf(subdividedBox(16, true));
  const WindingNumberTree tree(corners);
  ASSERT_GT(tree.nodeCount(), 1u);
  for (const glm::dvec3& p : randomPoints(200, glm::dvec3(-2.0), glm::dvec3(2.0), 17))
    EXPECT_NEAR(tree.exact(p), exactWindingNumber(corners, p), 1e-12);
}

/// The far-field terms of the whole soup about its area-weighted centroid c, computed directly
/// from the triangles (no tree): (1/4π)·[G(r)·N + Σ_ij ∂_j G_i(r) M_ij + ½ Σ_ijk ∂_j ∂_k G_i(r)
/// T_ijk], r = c − p, with M_ij = Σ a_i (g − c)_j and T_ijk = Σ ∫ n_i (x − c)_j (x − c)_k dA.
double directFarField(const std::vector<glm::dvec3>& corners, const glm::dvec3& p) {
  glm::dvec3 weighted(0.0);
  double area = 0;
  for (size_t k = 0; k < corners.size(); k += 3) {
    const double a =
        0.5 * glm::length(glm::cross(corners[k + 1] - corners[k], corners[k + 2] - corners[k]));
    weighted += a * (corners[k] + corners[k + 1] + corners[k + 2]) / 3.0;
    area += a;
  }
  const glm::dvec3 c = weighted / area;
  glm::dvec3 n(0.0);
  double m[3][3] = {}, t[3][3][3] = {};
  for (size_t k = 0; k < corners.size(); k += 3) {
    const glm::dvec3 v = 0.5 * glm::cross(corners[k + 1] - corners[k], corners[k + 2] - corners[k]);
    const glm::dvec3 q[3] = {corners[k] - c, corners[k + 1] - c, corners[k + 2] - c};
    const glm::dvec3 g = (q[0] + q[1] + q[2]) / 3.0, s = q[0] + q[1] + q[2];
    n += v;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        m[i][j] += v[i] * g[j];
        for (int l = 0; l < 3; ++l)  // ∫ δ_j δ_l dA = (a/12)(Σ q_j q_l + s_j s_l)
          t[i][j][l] += v[i] / 12.0 *
                        (q[0][j] * q[0][l] + q[1][j] * q[1][l] + q[2][j] * q[2][l] + s[j] * s[l]);
      }
  }
  const glm::dvec3 r = c - p;
  const double d = glm::length(r), d3 = d * d * d, d5 = d3 * d * d, d7 = d5 * d * d;
  double sum = glm::dot(r, n) / d3;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      sum += m[i][j] * ((i == j ? 1.0 : 0.0) / d3 - 3.0 * r[i] * r[j] / d5);
      for (int l = 0; l < 3; ++l) {
        const double dd = -3.0 * ((i == j) * r[l] + (i == l) * r[j] + (j == l) * r[i]) / d5 +
                          15.0 * r[i] * r[j] * r[l] / d7;
        sum += 0.5 * t[i][j][l] * dd;
      }
    }
  return sum / (4.0 * kPi);
}

TEST(WindingNumber, TreeFarFromTheSoupIsTheDirectTaylorExpansion) {
  // Far enough away the root alone is used: the moments the tree gathers bottom-up and the
  // terms it contracts ahead of time must give the expansion computed from the triangles.
  // 64,000 triangles: the tree's halves are built in parallel (kParallelBuildFrom).
  for (const int cells : {12, 80})
    for (const bool open : {true, false}) {
      const std::vector<glm::dvec3> corners = cornersOf(subdividedBox(cells, open));
      const WindingNumberTree tree(corners);
      for (const glm::dvec3& direction : randomPoints(20, glm::dvec3(-1.0), glm::dvec3(1.0), 19)) {
        const glm::dvec3 p = 20.0 * glm::normalize(direction);  // the box's radius is below 2
        const WindingValue v = tree.evaluate(p, 2.0);
        const double direct = directFarField(corners, p);
        EXPECT_NEAR(v.winding, direct, 1e-12 + 1e-9 * std::abs(direct));
        EXPECT_GT(v.errorBound, 0.0);
      }
    }
}

TEST(WindingNumber, ManyPointsGetTheValuesOfOnePointAtATime) {
  // The array form goes through the tree several points at a time (and re-evaluates near 0.5
  // with a larger beta): each point must get what evaluate(p, beta), a packet of one, gives
  // it, to the bit (a point's value does not depend on the points beside it), and that value
  // must be the exact sum within its bound (the traversal itself, checked independently).
  const std::vector<glm::dvec3> corners = cornersOf(subdividedBox(16, true));
  const WindingNumberTree tree(corners);
  std::vector<glm::dvec3> points = randomPoints(3001, glm::dvec3(-1.5), glm::dvec3(1.5), 23);
  points[5] = glm::dvec3(std::nan(""), 0.0, 0.0);
  for (int k = 0; k < 40; ++k) points.push_back(glm::dvec3(0.01 * k, -0.02 * k, 1.0));  // w ≈ 0.5
  std::vector<double> flat;
  for (const glm::dvec3& p : points) flat.insert(flat.end(), {p.x, p.y, p.z});
  std::vector<double> w(points.size()), bound(points.size());
  tree.evaluate(flat.data(), points.size(), 2.0, w.data(), bound.data());
  size_t refined = 0, far = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    WindingValue v = tree.evaluate(points[i], 2.0);
    if (std::abs(v.winding - 0.5) < kWindingRefineBand) {
      v = tree.evaluate(points[i], kWindingRefineFactor * 2.0);
      ++refined;
    }
    if (std::isnan(v.winding)) {
      EXPECT_TRUE(std::isnan(w[i]) && std::isnan(bound[i])) << i;
      continue;
    }
    EXPECT_EQ(w[i], v.winding) << i;
    EXPECT_EQ(bound[i], v.errorBound) << i;
    EXPECT_LE(std::abs(w[i] - exactWindingNumber(corners, points[i])), bound[i] + 1e-10) << i;
    far += bound[i] > 0;
  }
  EXPECT_GE(refined, 40u);
  EXPECT_GT(far, points.size() / 2);  // the far field was used
}

}  // namespace winding_test
}  // namespace aperture
