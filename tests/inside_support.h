#pragma once
// Helpers of the sign tests (tests/core/queries/test_inside.cpp, test_winding_number.cpp):
// meshes built from vertex and index lists, subdivided boxes with or without their top, the
// bunny with its holes filled, and points on a grid.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "tests/numerics_support.h"
#include "tests/query_support.h"

namespace aperture::test::inside {

using test::Loaded;  // a mesh and its scene: sceneOf(mesh)
using test::sceneOf;

/// An indexed mesh under construction (shared vertices), world coordinates in double.
struct MeshBuilder {
  std::vector<glm::dvec3> vertices;
  std::vector<uint32_t> indices;

  uint32_t vertex(const glm::dvec3& v) {
    vertices.push_back(v);
    return uint32_t(vertices.size() - 1);
  }
  void triangle(uint32_t a, uint32_t b, uint32_t c) { indices.insert(indices.end(), {a, b, c}); }
  Mesh mesh() const {
    Mesh m;
    m.name = "inside test";
    m.vertexCount = vertices.size();
    for (const glm::dvec3& v : vertices)
      for (int c = 0; c < 3; ++c) m.positions.push_back(float(v[c]));
    m.positions.resize(m.positions.size() + kVertexPaddingFloats, 0.0f);
    m.indices.assign(indices.begin(), indices.end());
    return m;
  }
};

/// The box [-1, 1]³, each side an n x n grid of quads split into two triangles, outward
/// counter-clockwise winding; without its top side (+z) when `open`. Each side has its own
/// vertices: the sides join by position only.
inline Mesh subdividedBox(int n, bool open) {
  MeshBuilder b;
  // Side s: the axis it faces and its sign; (u, v) span it so that u × v points outward.
  for (int axis = 0; axis < 3; ++axis)
    for (int sign = -1; sign <= 1; sign += 2) {
      if (open && axis == 2 && sign == 1) continue;
      const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
      const uint32_t first = uint32_t(b.vertices.size());
      for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
          glm::dvec3 p(0.0);
          p[axis] = sign;
          p[ua] = -1.0 + 2.0 * i / n;
          p[va] = -1.0 + 2.0 * j / n;
          b.vertex(p);
        }
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const uint32_t a = first + uint32_t(j * (n + 1) + i), c = a + 1, d = a + uint32_t(n + 1),
                         e = d + 1;
          if (sign > 0)
            b.triangle(a, c, e), b.triangle(a, e, d);
          else
            b.triangle(a, e, c), b.triangle(a, d, e);
        }
    }
  return b.mesh();
}

/// `mesh` with every boundary loop (edges used by one triangle) closed by a fan around the
/// loop's mean vertex, oriented to traverse each boundary edge the other way. Loops are
/// followed edge by edge from each unused boundary edge (a vertex with several outgoing
/// boundary edges takes the first one found).
inline Mesh holesFilled(const Mesh& mesh) {
  MeshBuilder b;
  for (size_t v = 0; v < mesh.vertexCount; ++v) b.vertex(glm::dvec3(mesh.vertex(v)));
  b.indices.assign(mesh.indices.begin(), mesh.indices.end());
  std::map<std::pair<uint32_t, uint32_t>, int> uses;  // directed edge -> count
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k)
      ++uses[{mesh.indices[3 * t + size_t(k)], mesh.indices[3 * t + size_t((k + 1) % 3)]}];
  std::multimap<uint32_t, uint32_t> boundaryFrom;  // reversed boundary edges b -> a
  for (const auto& [edge, count] : uses)
    if (!uses.count({edge.second, edge.first})) boundaryFrom.emplace(edge.second, edge.first);
  while (!boundaryFrom.empty()) {
    std::vector<uint32_t> loop;
    uint32_t at = boundaryFrom.begin()->first;
    while (true) {
      const auto it = boundaryFrom.find(at);
      if (it == boundaryFrom.end()) break;
      loop.push_back(at);
      at = it->second;
      boundaryFrom.erase(it);
    }
    if (loop.size() < 3) continue;
    glm::dvec3 centre(0.0);
    for (uint32_t v : loop) centre += b.vertices[v];
    const uint32_t c = b.vertex(centre / double(loop.size()));
    for (size_t k = 0; k < loop.size(); ++k) b.triangle(loop[k], loop[(k + 1) % loop.size()], c);
  }
  Mesh filled = b.mesh();
  filled.anchor = mesh.anchor;
  return filled;
}

/// The world corners of the scene's one mesh, 3 per triangle (an independent reading of the
/// mesh for the exact references).
inline std::vector<glm::dvec3> cornersOf(const Mesh& m) {
  std::vector<glm::dvec3> corners;
  for (uint32_t i : m.indices) corners.push_back(m.anchor + glm::dvec3(m.vertex(i)));
  return corners;
}

/// The distance from p to the nearest of the triangles of `corners` (3 per triangle), by
/// brute force over query_support's triangleDistance (not core's closest-point method).
inline double distanceToSoup(const std::vector<glm::dvec3>& corners, const glm::dvec3& p) {
  double best = INFINITY;
  for (size_t k = 0; k + 2 < corners.size(); k += 3)
    best =
        std::min(best, queries::triangleDistance(p, {corners[k], corners[k + 1], corners[k + 2]}));
  return best;
}

/// The points of a grid of `n` per axis over [lo, hi]³, x fastest, as 3 doubles each.
inline std::vector<double> gridPoints(double lo, double hi, int n) {
  std::vector<double> p;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (int c : {i, j, k}) p.push_back(lo + (hi - lo) * c / (n - 1));
  return p;
}

}  // namespace aperture::test::inside
