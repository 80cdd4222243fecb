#include "core/engine/cull.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <map>

#include "core/util/parallel.h"

namespace aperture {

namespace {

/// The world box of the mesh-space box [lo, hi] (relative to the anchor) under `worldFromMesh`:
/// the bounds of its eight transformed corners, computed in double.
void worldBox(const glm::dvec3& anchor, const glm::dmat4& worldFromMesh, bool identity,
              const glm::vec3& lo, const glm::vec3& hi, glm::dvec3& wlo, glm::dvec3& whi) {
  if (identity) {
    wlo = anchor + glm::dvec3(lo);
    whi = anchor + glm::dvec3(hi);
    return;
  }
  wlo = glm::dvec3(std::numeric_limits<double>::max());
  whi = -wlo;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 p(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
    const glm::dvec3 w(worldFromMesh * glm::dvec4(anchor + p, 1.0));
    wlo = glm::min(wlo, w);
    whi = glm::max(whi, w);
  }
}

}  // namespace

TriangleSubset cullTriangles(const Mesh& mesh, const std::vector<glm::dmat4>& placements,
                             const WorldBoxTest& test) {
  const size_t tris = mesh.triangleCount();
  std::vector<uint8_t> keep(tris, 0);
  std::vector<bool> identity;
  for (const glm::dmat4& m : placements) identity.push_back(m == glm::dmat4(1.0));
  auto mayBeSeen = [&](const glm::vec3& lo, const glm::vec3& hi) {
    for (size_t p = 0; p < placements.size(); ++p) {
      glm::dvec3 wlo, whi;
      worldBox(mesh.anchor, placements[p], identity[p], lo, hi, wlo, whi);
      if (test(wlo, whi)) return true;
    }
    return false;
  };
  auto triBox = [&](size_t t, glm::vec3& lo, glm::vec3& hi) {
    const glm::vec3 a = mesh.vertex(mesh.indices[3 * t]), b = mesh.vertex(mesh.indices[3 * t + 1]),
                    c = mesh.vertex(mesh.indices[3 * t + 2]);
    lo = glm::min(a, glm::min(b, c));
    hi = glm::max(a, glm::max(b, c));
  };
  const size_t clusters = (tris + kCullClusterSize - 1) / kCullClusterSize;
  parallelFor(clusters, 16, [&](size_t first, size_t last) {
    for (size_t c = first; c != last; ++c) {
      const size_t t0 = c * kCullClusterSize;
      const size_t t1 = std::min(t0 + kCullClusterSize, tris);
      glm::vec3 lo(std::numeric_limits<float>::max()), hi(-lo), a, b;
      for (size_t t = t0; t < t1; ++t) {
        triBox(t, a, b);
        lo = glm::min(lo, a);
        hi = glm::max(hi, b);
      }
      if (!mayBeSeen(lo, hi)) continue;
      for (size_t t = t0; t < t1; ++t) {
        triBox(t, a, b);
        keep[t] = mayBeSeen(a, b);
      }
    }
  });
  TriangleSubset s;
  const size_t kept = size_t(std::count(keep.begin(), keep.end(), uint8_t(1)));
  s.indices.reserve(3 * kept);
  s.primIds.reserve(kept);
  for (size_t t = 0; t < tris; ++t)
    if (keep[t]) {
      s.indices.insert(s.indices.end(), mesh.indices.begin() + std::ptrdiff_t(3 * t),
                       mesh.indices.begin() + std::ptrdiff_t(3 * t + 3));
      s.primIds.push_back(uint32_t(t));
    }
  return s;
}

CullStats cullObjects(std::vector<SceneObject>& objects, const WorldBoxTest& test,
                      std::deque<TriangleSubset>& storage) {
  const auto start = std::chrono::steady_clock::now();
  CullStats stats;
  std::map<const Mesh*, std::vector<glm::dmat4>> placements;
  std::vector<const Mesh*> order;  // meshes in first-use order, for a deterministic storage
  for (const SceneObject& o : objects) {
    if (!placements.count(o.mesh)) order.push_back(o.mesh);
    placements[o.mesh].push_back(o.worldFromMesh);
  }
  std::map<const Mesh*, const TriangleSubset*> done;
  for (const Mesh* m : order) {
    storage.push_back(cullTriangles(*m, placements[m], test));
    const TriangleSubset& s = storage.back();
    done[m] = &s;
    stats.trianglesBefore += m->triangleCount();
    stats.trianglesKept += s.triangleCount();
    stats.clustersTested += (m->triangleCount() + kCullClusterSize - 1) / kCullClusterSize;
    stats.subsetBytes += (s.indices.capacity() + s.primIds.capacity()) * sizeof(uint32_t);
  }
  for (SceneObject& o : objects) o.subset = done[o.mesh];
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace aperture
