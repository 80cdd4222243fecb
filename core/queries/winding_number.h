#pragma once
// The generalized winding number of a triangle soup (Jacobson, Kavan and Sorkine-Hornung,
// "Robust inside-outside segmentation using generalized winding numbers", 2013): at a point p,
//   w(p) = Σ_t Ω_t(p) / 4π,
// Ω_t the signed solid angle triangle t subtends at p (Van Oosterom and Strackee's formula, in
// double). For a closed, consistently oriented surface w is the number of times it winds
// around p (1 inside, 0 outside, 0.5 on the surface); for an open one it degrades gracefully
// and w > 0.5 is the inside people trust.
//
// The fast evaluation (WindingNumberTree) sums over a BVH of the triangles: a node of radius R
// (every corner of its triangles within R of its centre c) whose centre is farther from p than
// beta·R is replaced by the first three terms of the Taylor expansion of its double-layer
// potential about c (the dipole, second- and third-order terms); nodes closer than that are
// opened, and leaves (at most kWindingLeafTriangles triangles) are summed exactly. Scenes of
// at most kWindingExactBelow triangles are always summed exactly.
//
// Error bound. With y = x − p and G(y) = y / |y|³ = −∇(1/|y|), a node contributes
// (1/4π) ∫ G(x − p) · n dA, n the unit normal. Write x − p = r + δ with r = c − p, d = |r| and
// |δ| ≤ R. The Taylor series of G(r + δ) · n in δ has as its k-th term
// (1/k!) D^{k+1}(1/|·|)(r)[n, δ, ..., δ]. The j-th derivative of 1/|y| along a unit direction
// is j!·P_j(cos θ)/|y|^{j+1} (the Legendre expansion of 1/|y − δ|, |P_j| ≤ 1), and a symmetric
// multilinear form takes its norm on the diagonal, so the k-th term is at most
// (k+1)·|δ|^k / d^{k+2}. The expansion used here keeps k = 0 (the dipole), 1 and 2; the
// rest sums to at most Σ_{k≥3} (k+1)·Q^k / d² = Q³·(4 − 3Q) / ((1 − Q)²·d²) per unit area,
// Q = R/d < 1. A node of total (unsigned) area A used at distance d > beta·R therefore adds
// at most
//   e(node) = A·Q³·(4 − 3Q) / (4π·d²·(1 − Q)²)
// to the error, and the error of w(p) is at most the sum of e over the nodes the evaluation
// used (WindingValue::errorBound, computed alongside), plus double rounding (about 1e-15 per
// triangle). A priori each node's share is below A·(4β − 3) / (4π·β⁴·(β − 1)²·R²) (Q < 1/β):
// for beta = 2 and a flat node (A ≈ πR²) 5/64, and the shares of farther nodes fall as
// 1/d⁵. The bound is rigorous but not tight: the tests measure errors of a few percent of it
// (docs/queries.md, "Sign and occupancy").
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace aperture {

/// Scenes with at most this many triangles are summed exactly (no tree is used).
inline constexpr size_t kWindingExactBelow = 64;
/// The most triangles in a leaf of the tree (summed exactly when a leaf is opened).
inline constexpr size_t kWindingLeafTriangles = 8;

/// WindingNumberTree::evaluate's default band about 0.5 in which a point is evaluated again,
/// and the factor on beta it is evaluated with. The band is 8 times the worst error measured
/// at beta = 2 (docs/queries.md, "Sign and occupancy"): near an open mesh's holes w passes through
/// 0.5 away from the surface, and there the refined value decides the side.
inline constexpr double kWindingRefineBand = 0.05;
inline constexpr double kWindingRefineFactor = 4.0;

/// The signed solid angle (steradians, in (−2π, 2π]) that triangle (a, b, c) subtends at p:
/// positive when p lies behind it, on the side opposite to the normal (b − a) × (c − a) of its
/// counter-clockwise winding (inside a closed outward-oriented surface). Van Oosterom and
/// Strackee (1983): tan(Ω/2) = det[a′ b′ c′] / (|a′||b′||c′| + (a′·b′)|c′| + (b′·c′)|a′| +
/// (c′·a′)|b′|), a′ = a − p, ... 0 when p is a corner.
double triangleSolidAngle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                          const glm::dvec3& p);

/// Σ Ω / 4π over the triangles of `corners` (3 per triangle): the exact sum, in order.
double exactWindingNumber(const std::vector<glm::dvec3>& corners, const glm::dvec3& p);

/// A winding number and the bound on its truncation error (0 when summed exactly).
struct WindingValue {
  double winding = 0;
  double errorBound = 0;
};

/// The tree over a triangle soup, built once, evaluated at many points.
class WindingNumberTree {
 public:
  /// `corners`: 3 per triangle, world space (worldTriangleCorners).
  explicit WindingNumberTree(std::vector<glm::dvec3> corners);

  size_t triangleCount() const { return corners_.size() / 3; }
  size_t nodeCount() const { return nodes_.size(); }

  /// The exact sum at p (exactWindingNumber).
  double exact(const glm::dvec3& p) const { return exactWindingNumber(corners_, p); }
  /// The hierarchical evaluation at p with far-field parameter `beta` (> 1).
  WindingValue evaluate(const glm::dvec3& p, double beta) const;
  /// evaluate at `count` points (3 doubles each) on every core. A point whose w lands within
  /// `refineBand` of 0.5 (the inside threshold) is evaluated again with kWindingRefineFactor ·
  /// beta, and gets that value and bound. A point that is not finite gets NaN for both.
  /// `errorBound` may be null. Throws Error unless beta > 1 and finite.
  void evaluate(const double* points, size_t count, double beta, double* winding,
                double* errorBound, double refineBand = kWindingRefineBand) const;

 private:
  /// What traversal reads at every node it visits (48 bytes, so a cache line holds one).
  struct Node {
    glm::dvec3 centre{0.0};
    double radius = 0;
    uint32_t first = 0;  ///< first of its triangles in leaf order (corners_ after the build)
    uint32_t count = 0;  ///< leaf: triangles; 0 for an inner node
    uint32_t right = 0;  ///< inner node: the right child (the left one follows the node)
  };
  /// What a node contributes when it is far (read only then): the Taylor terms contracted
  /// ahead of time, so that evaluating them is a few polynomials in r = c − p.
  struct FarTerms {
    double normal[3] = {};     ///< Σ vector area: the dipole moment N
    double area = 0;           ///< Σ |vector area|: for the error bound
    double trace = 0;          ///< Σ_i M_ii, M_ij = Σ a_i (g − c)_j the second-order moment
    double quadratic[6] = {};  ///< r·M·r = Σ quadratic[q]·(xx, xy, xz, yy, yz, zz)[q]
    /// Σ_ik r_k (2 T_iik + T_kii): the third-order term's part in 1/d⁵, T_ijk = Σ ∫ n_i
    /// (x − c)_j (x − c)_k dA.
    double linear[3] = {};
    /// Σ_ijk r_i r_j r_k T_ijk = Σ cubic[m]·(xxx, xxy, xxz, xyy, xyz, xzz, yyy, yyz, yzz, zzz)[m].
    double cubic[10] = {};
  };
  struct Moments;  // a subtree's raw moments while the tree is built
  std::vector<glm::dvec3> corners_;
  glm::dvec3 lo_{INFINITY}, hi_{-INFINITY};  ///< the corners' box
  std::vector<uint32_t> order_;              ///< triangles in leaf order
  std::vector<Node> nodes_;
  std::vector<FarTerms> far_;  ///< parallel to nodes_

  /// Builds the subtree over order_[begin, end) into `nodes` and `far` (indices relative to
  /// their start); halves of at least kParallelBuildFrom triangles are built at once.
  static constexpr uint32_t kParallelBuildFrom = 1 << 15;
  Moments build(uint32_t begin, uint32_t end, const std::vector<glm::dvec3>& centroids,
                const std::vector<glm::dvec3>& vectorAreas, std::vector<Node>& nodes,
                std::vector<FarTerms>& far);
  Moments leafMoments(uint32_t begin, uint32_t end, const std::vector<glm::dvec3>& centroids,
                      const std::vector<glm::dvec3>& vectorAreas) const;
  /// The largest distance from `centre` to a corner of triangles [begin, end) of corners_.
  double radiusAbout(const glm::dvec3& centre, uint32_t begin, uint32_t end) const;
  static FarTerms farTerms(const Moments& m);
  /// How many points evaluatePacket takes at once.
  static constexpr int kPacket = 8;
  /// 4π times the winding number and its bound at the points of `lanes` (a bit per point of
  /// `points`; only those are read): the one traversal of the tree, which evaluate(p, beta)
  /// runs with one lane. A lane's value does not depend on the other lanes.
  void evaluatePacket(const glm::dvec3* points, unsigned lanes, double beta, double* sum,
                      double* bound) const;
  static double farField4Pi(const FarTerms& f, const glm::dvec3& r, double d);
};

}  // namespace aperture
