#include "core/triangle_order.h"

#include <array>
#include <cmath>
#include <utility>

#include "core/huge_pages.h"
#include "core/parallel.h"

namespace aperture {

namespace {

constexpr int kAxisBits = 10;  // 1024 cells per axis: 30-bit Morton codes
constexpr uint32_t kNonFiniteKey = uint32_t(1) << (3 * kAxisBits);
constexpr size_t kTrianglesPerTask = size_t(1) << 16;

/// The bits of `v` (kAxisBits of them) spread to every third bit.
uint32_t spreadBits(uint32_t v) {
  v &= 0x3FFu;
  v = (v | (v << 16)) & 0x030000FFu;
  v = (v | (v << 8)) & 0x0300F00Fu;
  v = (v | (v << 4)) & 0x030C30C3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

/// The Morton code of the grid cell holding each triangle's centroid.
std::vector<uint32_t> cellKeys(const Mesh& m) {
  constexpr int kGrid = 1 << kAxisBits;
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  const glm::vec3 scale = float(kGrid) / glm::max(hi - lo, glm::vec3(1e-30f));
  std::vector<uint32_t> keys(m.triangleCount());
  parallelFor(keys.size(), kTrianglesPerTask, [&](size_t begin, size_t end) {
    for (size_t t = begin; t < end; ++t) {
      const uint32_t* corner = &m.indices[3 * t];
      const glm::vec3 centroid =
          (m.vertex(corner[0]) + m.vertex(corner[1]) + m.vertex(corner[2])) / 3.0f;
      if (!std::isfinite(centroid.x + centroid.y + centroid.z)) {
        keys[t] = kNonFiniteKey;
        continue;
      }
      const glm::ivec3 cell = glm::clamp(glm::ivec3((centroid - lo) * scale), 0, kGrid - 1);
      keys[t] = spreadBits(uint32_t(cell.x)) | spreadBits(uint32_t(cell.y)) << 1 |
                spreadBits(uint32_t(cell.z)) << 2;
    }
  });
  return keys;
}

/// The triangle indices in ascending order of `keys`, ties in index order: a least-significant
/// digit radix sort, two stable passes of 16 bits.
std::vector<uint32_t> stableOrderOf(std::vector<uint32_t> keys) {
  constexpr size_t kBuckets = size_t(1) << 16;
  const size_t n = keys.size();
  std::vector<uint32_t> order(n), keysOut(n), orderOut(n);
  for (size_t t = 0; t < n; ++t) order[t] = uint32_t(t);
  for (int shift = 0; shift < 32; shift += 16) {
    std::vector<size_t> next(kBuckets, 0);
    for (uint32_t k : keys) ++next[(k >> shift) & (kBuckets - 1)];
    size_t sum = 0;
    for (size_t& c : next) sum += std::exchange(c, sum);
    for (size_t t = 0; t < n; ++t) {
      const size_t at = next[(keys[t] >> shift) & (kBuckets - 1)]++;
      keysOut[at] = keys[t];
      orderOut[at] = order[t];
    }
    keys.swap(keysOut);
    order.swap(orderOut);
  }
  return order;
}

/// values[order[k]] at k, in parallel; `stride` values per triangle.
template <size_t kStride>
void gather(std::vector<uint32_t>& values, const std::vector<uint32_t>& order) {
  std::vector<uint32_t> moved;
  resizeOnHugePages(moved, values.size());
  parallelFor(order.size(), kTrianglesPerTask, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k)
      for (size_t c = 0; c < kStride; ++c) moved[kStride * k + c] = values[kStride * order[k] + c];
  });
  values.swap(moved);
}

}  // namespace

bool scatteredForChunks(const Mesh& mesh, const BuildOptions& options) {
  const size_t chunk = options.effectiveChunkTriangles();
  if (chunk == 0 || mesh.triangleCount() <= chunk) return false;
  return chunksPerCell(mesh, mesh.indices.data(), mesh.triangleCount(), chunk) >
         options.maxChunksPerCell;
}

void orderTrianglesInSpace(Mesh& mesh) {
  std::vector<uint32_t> order = stableOrderOf(cellKeys(mesh));
  gather<3>(mesh.indices, order);
  for (MeshProperty& p : mesh.properties)
    if (p.domain == PropertyDomain::Face) gather<1>(p.values, order);
  if (!mesh.sourceTriangles.empty())
    gather<1>(mesh.sourceTriangles, order);
  else
    mesh.sourceTriangles = std::move(order);
}

std::vector<uint32_t> storedTriangles(const Mesh& mesh) {
  std::vector<uint32_t> stored(mesh.sourceTriangles.size());
  for (size_t t = 0; t < stored.size(); ++t) stored[mesh.sourceTriangles[t]] = uint32_t(t);
  return stored;
}

}  // namespace aperture
