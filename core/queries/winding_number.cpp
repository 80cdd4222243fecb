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

/// The far-field terms of a node at r = c − p, d = |r|: (1/4π)·[G(r)·N + Σ_ij ∂_j G_i(r) M_ij
/// + ½ Σ_ijk ∂_j ∂_k G_i(r) T_ijk], G(y) = y/|y|³, with
///   ∂_j G_i = δ_ij/d³ − 3 r_i r_j/d⁵,
///   ∂_j ∂_k G_i = −3 (δ_ij r_k + δ_ik r_j + δ_jk r_i)/d⁵ + 15 r_i r_j r_k/d⁷.
double farField(const glm::dvec3& r, double d, const glm::dvec3& normal, const double* m,
                const double* t) {
  const double d2 = d * d, d3 = d2 * d, d5 = d3 * d2, d7 = d5 * d2;
  const double dipole = glm::dot(r, normal) / d3;
  const double trace = m[0] + m[4] + m[8];
  const glm::dvec3 mr(m[0] * r.x + m[1] * r.y + m[2] * r.z, m[3] * r.x + m[4] * r.y + m[5] * r.z,
                      m[6] * r.x + m[7] * r.y + m[8] * r.z);
  const double second = trace / d3 - 3.0 * glm::dot(r, mr) / d5;
  double contracted = 0, traced = 0, cubic = 0;  // Σ r_k T_iik, Σ r_i T_ijj, Σ r_i r_j r_k T_ijk
  for (int i = 0; i < 3; ++i) {
    const double* ti = t + 6 * i;
    for (int k = 0; k < 3; ++k) contracted += r[k] * ti[kPair[i][k]];
    traced += r[i] * (ti[0] + ti[3] + ti[5]);
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) cubic += r[i] * r[j] * r[k] * ti[kPair[j][k]];
  }
  const double third = 0.5 * (-3.0 * (2.0 * contracted + traced) / d5 + 15.0 * cubic / d7);
  return (dipole + second + third) / kFourPi;
}

/// The bound on the error of farField for a node of total area `area` and radius `radius` at
/// distance d: (1/4π)·A·Σ_{k≥3} (k+1)·Q^k / d², Q = R/d (winding_number.h).
double truncationBound(double area, double radius, double d) {
  const double q = radius / d, rest = 1.0 - q;
  return area * q * q * q * (4.0 - 3.0 * q) / (kFourPi * d * d * rest * rest);
}

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
  nodes_.reserve(2 * (triangles / kWindingLeafTriangles + 1));
  build(0, uint32_t(triangles), centroids, vectorAreas);
}

void WindingNumberTree::summarise(Node& node, uint32_t begin, uint32_t end,
                                  const std::vector<glm::dvec3>& centroids,
                                  const std::vector<glm::dvec3>& vectorAreas) const {
  glm::dvec3 weighted(0.0), mean(0.0);
  double area = 0;
  for (uint32_t k = begin; k < end; ++k) {
    const uint32_t t = order_[k];
    const double a = glm::length(vectorAreas[t]);
    weighted += a * centroids[t];
    mean += centroids[t];
    area += a;
    node.normal += vectorAreas[t];
  }
  node.area = area;
  node.centre = area > 0 ? weighted / area : mean / double(end - begin);
  double radius2 = 0;
  for (uint32_t at = begin; at < end; ++at) {
    const uint32_t t = order_[at];
    for (int i = 0; i < 3; ++i) {
      const glm::dvec3 e = corners_[3 * size_t(t) + size_t(i)] - node.centre;
      radius2 = std::max(radius2, glm::dot(e, e));
    }
    const glm::dvec3 g = centroids[t] - node.centre, &n = vectorAreas[t];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) node.moment[3 * i + j] += n[i] * g[j];
    // ∫ δ δᵀ dA over the triangle = (area/12)·(Σ_a p_a p_aᵀ + s sᵀ), p_a its corners less the
    // centre, s = Σ_a p_a; times the unit normal: the vector area over 12.
    glm::dvec3 p[3];
    for (int a = 0; a < 3; ++a) p[a] = corners_[3 * size_t(t) + size_t(a)] - node.centre;
    const glm::dvec3 sum = p[0] + p[1] + p[2];
    double second[6];
    for (int j = 0; j < 3; ++j)
      for (int k = j; k < 3; ++k)
        second[kPair[j][k]] =
            p[0][j] * p[0][k] + p[1][j] * p[1][k] + p[2][j] * p[2][k] + sum[j] * sum[k];
    for (int i = 0; i < 3; ++i)
      for (int q = 0; q < 6; ++q) node.third[6 * i + q] += n[i] * second[q] / 12.0;
  }
  node.radius = std::sqrt(radius2);
}

uint32_t WindingNumberTree::build(uint32_t begin, uint32_t end,
                                  const std::vector<glm::dvec3>& centroids,
                                  const std::vector<glm::dvec3>& vectorAreas) {
  const uint32_t index = uint32_t(nodes_.size());
  nodes_.emplace_back();
  Node node;
  summarise(node, begin, end, centroids, vectorAreas);
  if (end - begin <= kWindingLeafTriangles) {
    node.first = begin, node.count = end - begin;
    nodes_[index] = node;
    return index;
  }
  // Median split of the centroids along the longest axis of their box.
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (uint32_t k = begin; k < end; ++k) {
    lo = glm::min(lo, centroids[order_[k]]);
    hi = glm::max(hi, centroids[order_[k]]);
  }
  const glm::dvec3 extent = hi - lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
  const uint32_t middle = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                   [&](uint32_t a, uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
  build(begin, middle, centroids, vectorAreas);
  node.right = build(middle, end, centroids, vectorAreas);
  nodes_[index] = node;
  return index;
}

WindingValue WindingNumberTree::evaluate(const glm::dvec3& p, double beta) const {
  WindingValue value;
  if (!finitePoint(p)) {
    value.winding = value.errorBound = std::numeric_limits<double>::quiet_NaN();
    return value;
  }
  if (nodes_.empty()) {
    value.winding = exact(p);
    return value;
  }
  double solidAngles = 0, far = 0, bound = 0;
  uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const uint32_t index = stack[--top];
    const Node& node = nodes_[index];
    const glm::dvec3 r = node.centre - p;
    const double d = glm::length(r);
    if (d > beta * node.radius) {
      far += farField(r, d, node.normal, node.moment, node.third);
      bound += truncationBound(node.area, node.radius, d);
    } else if (node.count > 0) {
      for (uint32_t k = node.first; k < node.first + node.count; ++k) {
        const size_t t = order_[k];
        solidAngles +=
            triangleSolidAngle(corners_[3 * t], corners_[3 * t + 1], corners_[3 * t + 2], p);
      }
    } else {
      stack[top++] = node.right;
      stack[top++] = index + 1;
    }
  }
  value.winding = solidAngles / kFourPi + far;
  value.errorBound = bound;
  return value;
}

void WindingNumberTree::evaluate(const double* points, size_t count, double beta, double* winding,
                                 double* errorBound, double refineBand) const {
  if (!(beta > 1.0) || !std::isfinite(beta))
    throw Error(cat("winding number: beta ", beta, " must be a finite number above 1"));
  // In Morton order over the triangles' box: consecutive points open the same nodes, which
  // then come from the cache.
  const std::vector<size_t> order = mortonOrder(points, count, lo_, hi_);
  parallelFor(count, 256, [&](size_t begin, size_t end) {
    for (size_t at = begin; at < end; ++at) {
      const size_t i = order[at];
      const glm::dvec3 p(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
      WindingValue v = evaluate(p, beta);
      if (std::abs(v.winding - 0.5) < refineBand) v = evaluate(p, kWindingRefineFactor * beta);
      winding[i] = v.winding;
      if (errorBound) errorBound[i] = v.errorBound;
    }
  });
}

}  // namespace aperture
