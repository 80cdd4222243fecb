#include "core/queries/winding_number.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/queries/morton_order.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace aperture {

namespace {

constexpr double kFourPi = 4.0 * 3.14159265358979323846;

bool finitePoint(const glm::dvec3& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

/// Index of the pair (j, k), j <= k, in a symmetric 3 x 3 matrix stored as xx xy xz yy yz zz.
constexpr int kPair[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};

/// The index of the monomial r_i r_j r_k in (xxx, xxy, xxz, xyy, xyz, xzz, yyy, yyz, yzz, zzz).
int cubicIndex(int i, int j, int k) {
  int s[3] = {i, j, k};
  std::sort(s, s + 3);
  constexpr int kFirst[3] = {0, 6, 9};  // where the monomials starting with x, y, z begin
  return kFirst[s[0]] + kPair[s[1]][s[2]] - kPair[s[0]][s[0]];
}

/// 4π times the bound on the error of the far-field terms for a node of total area `area` and
/// radius `radius` at distance d: A·Σ_{k≥3} (k+1)·Q^k / d², Q = R/d (winding_number.h).
double truncationBound4Pi(double area, double radius, double d) {
  const double q = radius / d, rest = 1.0 - q;
  return area * q * q * q * (4.0 - 3.0 * q) / (d * d * rest * rest);
}

/// The winding number and its bound from their sums times 4π (what traversal adds up).
WindingValue valueOf4Pi(double sum, double bound) { return {sum / kFourPi, bound / kFourPi}; }

}  // namespace

double triangleSolidAngle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                          const glm::dvec3& p) {
  const glm::dvec3 x = a - p, y = b - p, z = c - p;
  const double lx = glm::length(x), ly = glm::length(y), lz = glm::length(z);
  const double det = glm::dot(x, glm::cross(y, z));
  const double den = lx * ly * lz + glm::dot(x, y) * lz + glm::dot(y, z) * lx + glm::dot(z, x) * ly;
  return 2.0 * std::atan2(det, den);
}

double exactWindingNumber(const std::vector<glm::dvec3>& corners, const glm::dvec3& p) {
  double sum = 0;
  for (size_t k = 0; k + 2 < corners.size(); k += 3)
    sum += triangleSolidAngle(corners[k], corners[k + 1], corners[k + 2], p);
  return sum / kFourPi;
}

/// A subtree's moments about its centre while the tree is built (winding_number.h's Node and
/// FarTerms hold what evaluation needs of them).
struct WindingNumberTree::Moments {
  glm::dvec3 weighted{0.0};     ///< Σ a·g, a a triangle's area and g its centroid
  glm::dvec3 centroidSum{0.0};  ///< Σ g
  double triangles = 0;         ///< how many
  double area = 0;              ///< Σ a
  glm::dvec3 normal{0.0};       ///< Σ vector area
  glm::dvec3 centre{0.0};       ///< area-weighted centroid (the plain mean without area)
  double moment[9] = {};        ///< M_ij = Σ a_i (g − c)_j, row-major
  double third[18] = {};        ///< T_ijk = Σ ∫ n_i (x − c)_j (x − c)_k dA, (j, k) as kPair

  void centreFromSums() { centre = area > 0 ? weighted / area : centroidSum / triangles; }
  /// Adds a child's moments, moved from its centre to this one: with e = c′ − c,
  /// M_ij += M′_ij + N′_i e_j and T_ijk += T′_ijk + M′_ij e_k + M′_ik e_j + N′_i e_j e_k.
  void addMoved(const Moments& child) {
    const glm::dvec3 e = child.centre - centre;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        moment[3 * i + j] += child.moment[3 * i + j] + child.normal[i] * e[j];
      for (int j = 0; j < 3; ++j)
        for (int k = j; k < 3; ++k)
          third[6 * i + kPair[j][k]] +=
              child.third[6 * i + kPair[j][k]] + child.moment[3 * i + j] * e[k] +
              child.moment[3 * i + k] * e[j] + child.normal[i] * e[j] * e[k];
    }
  }
};

WindingNumberTree::WindingNumberTree(std::vector<glm::dvec3> corners)
    : corners_(std::move(corners)) {
  const size_t triangles = triangleCount();
  for (const glm::dvec3& c : corners_) lo_ = glm::min(lo_, c), hi_ = glm::max(hi_, c);
  if (triangles > std::numeric_limits<uint32_t>::max() / 2)
    throw Error(cat("winding number: ", triangles, " triangles is more than the tree holds"));
  if (triangles <= kWindingExactBelow) return;
  std::vector<glm::dvec3> centroids(triangles), vectorAreas(triangles);
  parallelFor(triangles, 1 << 14, [&](size_t begin, size_t end) {
    for (size_t t = begin; t < end; ++t) {
      const glm::dvec3 &a = corners_[3 * t], &b = corners_[3 * t + 1], &c = corners_[3 * t + 2];
      centroids[t] = (a + b + c) / 3.0;
      vectorAreas[t] = 0.5 * glm::cross(b - a, c - a);
    }
  });
  order_.resize(triangles);
  for (size_t t = 0; t < triangles; ++t) order_[t] = uint32_t(t);
  // Median splits leave at least kWindingLeafTriangles / 2 triangles in a leaf.
  const size_t nodes = 4 * (triangles / kWindingLeafTriangles + 1);
  nodes_.reserve(nodes);
  far_.reserve(nodes);
  build(0, uint32_t(triangles), centroids, vectorAreas, nodes_, far_);
  // The corners in leaf order: a leaf's triangles are then contiguous.
  std::vector<glm::dvec3> sorted(corners_.size());
  parallelFor(triangles, 1 << 14, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k)
      for (size_t i = 0; i < 3; ++i) sorted[3 * k + i] = corners_[3 * size_t(order_[k]) + i];
  });
  corners_.swap(sorted);
  order_ = std::vector<uint32_t>();
  // Each node's radius about its centre, from its triangles' corners, now contiguous.
  std::vector<uint32_t> ends(nodes_.size());
  for (size_t i = nodes_.size(); i-- > 0;) {
    const Node& node = nodes_[i];
    ends[i] = node.count > 0 ? node.first + node.count : ends[node.right];
  }
  parallelFor(nodes_.size(), 1 << 10, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      nodes_[i].radius = radiusAbout(nodes_[i].centre, nodes_[i].first, ends[i]);
  });
}

WindingNumberTree::Moments WindingNumberTree::leafMoments(
    uint32_t begin, uint32_t end, const std::vector<glm::dvec3>& centroids,
    const std::vector<glm::dvec3>& vectorAreas) const {
  Moments m;
  for (uint32_t k = begin; k < end; ++k) {
    const uint32_t t = order_[k];
    const double a = glm::length(vectorAreas[t]);
    m.weighted += a * centroids[t];
    m.centroidSum += centroids[t];
    m.area += a;
    m.normal += vectorAreas[t];
  }
  m.triangles = double(end - begin);
  m.centreFromSums();
  for (uint32_t at = begin; at < end; ++at) {
    const uint32_t t = order_[at];
    const glm::dvec3 g = centroids[t] - m.centre, &n = vectorAreas[t];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m.moment[3 * i + j] += n[i] * g[j];
    // ∫ δ δᵀ dA over the triangle = (area/12)·(Σ_a p_a p_aᵀ + s sᵀ), p_a its corners less the
    // centre, s = Σ_a p_a; times the unit normal: the vector area over 12.
    glm::dvec3 p[3];
    for (int a = 0; a < 3; ++a) p[a] = corners_[3 * size_t(t) + size_t(a)] - m.centre;
    const glm::dvec3 sum = p[0] + p[1] + p[2];
    double second[6];
    for (int j = 0; j < 3; ++j)
      for (int k = j; k < 3; ++k)
        second[kPair[j][k]] =
            p[0][j] * p[0][k] + p[1][j] * p[1][k] + p[2][j] * p[2][k] + sum[j] * sum[k];
    for (int i = 0; i < 3; ++i)
      for (int q = 0; q < 6; ++q) m.third[6 * i + q] += n[i] * second[q] / 12.0;
  }
  return m;
}

double WindingNumberTree::radiusAbout(const glm::dvec3& centre, uint32_t begin,
                                      uint32_t end) const {
  double radius2 = 0;
  for (size_t t = begin; t < end; ++t) {
    for (size_t i = 0; i < 3; ++i) {
      const glm::dvec3 e = corners_[3 * t + i] - centre;
      radius2 = std::max(radius2, glm::dot(e, e));
    }
  }
  return std::sqrt(radius2);
}

WindingNumberTree::Moments WindingNumberTree::build(uint32_t begin, uint32_t end,
                                                    const std::vector<glm::dvec3>& centroids,
                                                    const std::vector<glm::dvec3>& vectorAreas,
                                                    std::vector<Node>& nodes,
                                                    std::vector<FarTerms>& far) {
  const uint32_t index = uint32_t(nodes.size());
  nodes.emplace_back();
  far.emplace_back();
  Node node;
  node.first = begin;  // an inner node's too: its radius is found from it after the build
  Moments m;
  if (end - begin <= kWindingLeafTriangles) {
    m = leafMoments(begin, end, centroids, vectorAreas);
    node.count = end - begin;
  } else {
    // Median split of the centroids along the longest axis of their box.
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
    for (uint32_t k = begin; k < end; ++k) {
      lo = glm::min(lo, centroids[order_[k]]);
      hi = glm::max(hi, centroids[order_[k]]);
    }
    const glm::dvec3 extent = hi - lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0
                     : extent.y >= extent.z                       ? 1
                                                                  : 2;
    const uint32_t middle = begin + (end - begin) / 2;
    std::nth_element(
        order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
        [&](uint32_t a, uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
    Moments left, right;
    if (end - begin < kParallelBuildFrom) {
      left = build(begin, middle, centroids, vectorAreas, nodes, far);
      node.right = uint32_t(nodes.size());
      right = build(middle, end, centroids, vectorAreas, nodes, far);
    } else {
      // The two halves at once, the right one into its own arrays, appended after the left.
      std::vector<Node> rightNodes;
      std::vector<FarTerms> rightFar;
      rightNodes.reserve(4 * ((end - middle) / kWindingLeafTriangles + 1));
      rightFar.reserve(rightNodes.capacity());
      parallelFor(2, 1, [&](size_t first, size_t last) {
        for (size_t half = first; half < last; ++half)
          if (half == 0)
            left = build(begin, middle, centroids, vectorAreas, nodes, far);
          else
            right = build(middle, end, centroids, vectorAreas, rightNodes, rightFar);
      });
      node.right = uint32_t(nodes.size());
      for (Node n : rightNodes) {
        if (n.count == 0) n.right += node.right;
        nodes.push_back(n);
      }
      far.insert(far.end(), rightFar.begin(), rightFar.end());
    }
    for (const Moments* child : {&left, &right}) {
      m.weighted += child->weighted;
      m.centroidSum += child->centroidSum;
      m.triangles += child->triangles;
      m.area += child->area;
      m.normal += child->normal;
    }
    m.centreFromSums();
    m.addMoved(left);
    m.addMoved(right);
  }
  node.centre = m.centre;
  nodes[index] = node;
  far[index] = farTerms(m);
  return m;
}

WindingNumberTree::FarTerms WindingNumberTree::farTerms(const Moments& m) {
  FarTerms f;
  for (int i = 0; i < 3; ++i) f.normal[i] = m.normal[i];
  f.area = m.area;
  const double* M = m.moment;
  f.trace = M[0] + M[4] + M[8];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) f.quadratic[kPair[i][j]] += M[3 * i + j];
  for (int i = 0; i < 3; ++i) {
    const double* t = m.third + 6 * i;
    for (int k = 0; k < 3; ++k) f.linear[k] += 2.0 * t[kPair[i][k]];
    f.linear[i] += t[0] + t[3] + t[5];
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) f.cubic[cubicIndex(i, j, k)] += t[kPair[j][k]];
  }
  return f;
}

/// 4π times the far-field terms of a node at r = c − p, d = |r|: G(r)·N + Σ_ij ∂_j G_i(r) M_ij
/// + ½ Σ_ijk ∂_j ∂_k G_i(r) T_ijk, G(y) = y/|y|³, with
///   ∂_j G_i = δ_ij/d³ − 3 r_i r_j/d⁵,
///   ∂_j ∂_k G_i = −3 (δ_ij r_k + δ_ik r_j + δ_jk r_i)/d⁵ + 15 r_i r_j r_k/d⁷,
/// that is (N·r + tr M)/d³ − (3 r·M·r + (3/2) Σ_ik r_k (2 T_iik + T_kii))/d⁵ + (15/2) Σ_ijk
/// r_i r_j r_k T_ijk/d⁷.
inline double WindingNumberTree::farField4Pi(const FarTerms& f, const glm::dvec3& r, double d) {
  const double x = r.x, y = r.y, z = r.z;
  const double xx = x * x, yy = y * y, zz = z * z;
  const double dipole = f.normal[0] * x + f.normal[1] * y + f.normal[2] * z + f.trace;
  const double* q = f.quadratic;
  const double quadratic =
      q[0] * xx + q[1] * x * y + q[2] * x * z + q[3] * yy + q[4] * y * z + q[5] * zz;
  const double linear = f.linear[0] * x + f.linear[1] * y + f.linear[2] * z;
  const double* c = f.cubic;
  const double cubic =
      x * (c[0] * xx + c[1] * x * y + c[2] * x * z + c[3] * yy + c[4] * y * z + c[5] * zz) +
      y * (c[6] * yy + c[7] * y * z + c[8] * zz) + c[9] * zz * z;
  const double inverse2 = 1.0 / (d * d), inverse3 = inverse2 / d;
  return inverse3 *
         (dipole + inverse2 * (-3.0 * quadratic - 1.5 * linear + 7.5 * cubic * inverse2));
}

WindingValue WindingNumberTree::evaluate(const glm::dvec3& p, double beta) const {
  if (!finitePoint(p)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan};
  }
  if (nodes_.empty()) return {exact(p), 0.0};
  // A packet of one: lane 0 alone reads `points`.
  double sum[kPacket], bound[kPacket];
  evaluatePacket(&p, 1u, beta, sum, bound);
  return valueOf4Pi(sum[0], bound[0]);
}

void WindingNumberTree::evaluatePacket(const glm::dvec3* points, unsigned lanes, double beta,
                                       double* sum, double* bound) const {
  // Depth first, left child first, for up to kPacket points at once: a node is visited with
  // the lanes that reach it; a lane farther than beta·radius from its centre adds its
  // far-field terms, the others open it (or sum its triangles, at a leaf). Each lane adds its
  // terms in the same order whichever lanes share its packet, so a point's value does not
  // depend on them (a packet of one is evaluate(p, beta)). The points share each node's loads.
  for (int l = 0; l < kPacket; ++l) sum[l] = bound[l] = 0;
  struct Entry {
    uint32_t index;
    unsigned lanes;
  };
  Entry stack[128];
  int top = 0;
  stack[top++] = {0, lanes};
  while (top > 0) {
    const Entry entry = stack[--top];
    const Node& node = nodes_[entry.index];
    const double reach = beta * node.radius;
    unsigned far = 0, near = 0;
    glm::dvec3 r[kPacket];
    double d[kPacket];
    for (int l = 0; l < kPacket; ++l) {
      if (!(entry.lanes >> l & 1u)) continue;
      r[l] = node.centre - points[l];
      d[l] = glm::length(r[l]);
      (d[l] > reach ? far : near) |= 1u << l;
    }
    if (far) {
      const FarTerms& f = far_[entry.index];
      for (int l = 0; l < kPacket; ++l)
        if (far >> l & 1u) {
          sum[l] += farField4Pi(f, r[l], d[l]);
          bound[l] += truncationBound4Pi(f.area, node.radius, d[l]);
        }
    }
    if (!near) continue;
    if (node.count > 0) {
      const glm::dvec3* c = corners_.data() + 3 * size_t(node.first);
      for (uint32_t k = 0; k < node.count; ++k, c += 3)
        for (int l = 0; l < kPacket; ++l)
          if (near >> l & 1u) sum[l] += triangleSolidAngle(c[0], c[1], c[2], points[l]);
    } else {
      for (const uint32_t child : {node.right, entry.index + 1})
        for (int line = 0; line < int(sizeof(FarTerms)); line += 64)
          __builtin_prefetch(reinterpret_cast<const char*>(&far_[child]) + line);
      stack[top++] = {node.right, near};
      stack[top++] = {entry.index + 1, near};
    }
  }
}

void WindingNumberTree::evaluate(const double* points, size_t count, double beta, double* winding,
                                 double* errorBound, double refineBand) const {
  if (!(beta > 1.0) || !std::isfinite(beta))
    throw Error(cat("winding number: beta ", beta, " must be a finite number above 1"));
  // In Morton order over the triangles' box: consecutive points open the same nodes, which
  // then come from the cache, and go through the tree together (evaluatePacket).
  const std::vector<size_t> order = mortonOrder(points, count, lo_, hi_);
  auto store = [&](size_t i, const WindingValue& v) {
    winding[i] = v.winding;
    if (errorBound) errorBound[i] = v.errorBound;
  };
  parallelFor(count, 256, [&](size_t begin, size_t end) {
    for (size_t at = begin; at < end; at += kPacket) {
      const int n = int(std::min(end - at, size_t(kPacket)));
      glm::dvec3 p[kPacket];
      unsigned lanes = 0;
      for (int l = 0; l < n; ++l) {
        const size_t i = order[at + size_t(l)];
        p[l] = glm::dvec3(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
        if (nodes_.empty() || !finitePoint(p[l]))
          store(i, evaluate(p[l], beta));  // NaN, or the exact sum without a tree
        else
          lanes |= 1u << l;
      }
      if (!lanes) continue;
      double sum[kPacket], bound[kPacket];
      evaluatePacket(p, lanes, beta, sum, bound);
      unsigned refine = 0;
      for (int l = 0; l < n; ++l)
        if (lanes >> l & 1u) {
          const WindingValue v = valueOf4Pi(sum[l], bound[l]);
          if (std::abs(v.winding - 0.5) < refineBand)
            refine |= 1u << l;
          else
            store(order[at + size_t(l)], v);
        }
      if (!refine) continue;
      evaluatePacket(p, refine, kWindingRefineFactor * beta, sum, bound);
      for (int l = 0; l < n; ++l)
        if (refine >> l & 1u) store(order[at + size_t(l)], valueOf4Pi(sum[l], bound[l]));
    }
  });
}

}  // namespace aperture
