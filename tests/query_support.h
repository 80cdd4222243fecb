#pragma once
// What the point and ray query tests (tests/core/queries/test_closest_points.cpp,
// test_ray_hits.cpp) compare against: every placed triangle of a scene in world space, in
// double, and distances computed independently of core/queries (projection onto the plane,
// else the nearest edge).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
#include <limits>
#include <vector>

#include "core/engine/scene.h"

namespace aperture::test::queries {

/// A placed triangle in world space, with its object and its primID as loaded.
struct WorldTriangle {
  std::array<glm::dvec3, 3> v;
  unsigned object;
  uint32_t primId;
};

/// Every triangle of every object, world = worldFromMesh · (anchor + position).
inline std::vector<WorldTriangle> worldTriangles(const Scene& scene) {
  std::vector<WorldTriangle> out;
  for (unsigned o = 0; o < scene.objects().size(); ++o) {
    const SceneObject& so = scene.objects()[o];
    const Mesh& m = *so.mesh;
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      WorldTriangle w;
      for (int c = 0; c < 3; ++c) {
        const size_t k = m.indices[3 * t + size_t(c)];
        const glm::dvec3 local = m.anchor + glm::dvec3(m.positions[3 * k], m.positions[3 * k + 1],
                                                       m.positions[3 * k + 2]);
        w.v[size_t(c)] = glm::dvec3(so.worldFromMesh * glm::dvec4(local, 1.0));
      }
      w.object = o;
      w.primId = m.sourceTriangle(t);
      out.push_back(w);
    }
  }
  return out;
}

/// Distance from p to segment [a, b].
inline double segmentDistance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + t * ab));
}

/// Distance from p to the triangle: to its plane when the foot of the perpendicular lies
/// inside (all three edge functions of one sign), else to the nearest edge.
inline double triangleDistance(const glm::dvec3& p, const std::array<glm::dvec3, 3>& v) {
  const glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
  const double n2 = glm::dot(n, n);
  if (n2 > 0) {
    const glm::dvec3 foot = p - glm::dot(p - v[0], n) / n2 * n;
    const double e0 = glm::dot(glm::cross(v[1] - v[0], foot - v[0]), n);
    const double e1 = glm::dot(glm::cross(v[2] - v[1], foot - v[1]), n);
    const double e2 = glm::dot(glm::cross(v[0] - v[2], foot - v[2]), n);
    if (e0 >= 0 && e1 >= 0 && e2 >= 0) return std::fabs(glm::dot(p - v[0], n)) / std::sqrt(n2);
  }
  return std::min({segmentDistance(p, v[0], v[1]), segmentDistance(p, v[1], v[2]),
                   segmentDistance(p, v[2], v[0])});
}

/// The smallest triangleDistance over `triangles`.
inline double bruteForceDistance(const glm::dvec3& p, const std::vector<WorldTriangle>& triangles) {
  double best = std::numeric_limits<double>::infinity();
  for (const WorldTriangle& t : triangles) best = std::min(best, triangleDistance(p, t.v));
  return best;
}

}  // namespace aperture::test::queries
