#include "core/engine/triangle_order.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/util/huge_pages.h"
#include "core/util/morton.h"
#include "core/util/parallel.h"

namespace aperture {

namespace {

constexpr int kAxisBits = 5;  // 32 cells per axis: 15-bit Morton codes
constexpr uint16_t kNonFiniteKey = uint16_t(1) << (3 * kAxisBits);  // sorts last
constexpr size_t kBuckets = size_t(kNonFiniteKey) + 1;
constexpr size_t kTrianglesPerBlock = size_t(1) << 22;

/// The Morton code of the 32³ cell holding each centroid, from its centroidCells cell (the
/// 64³ grid's cells, two to a side in each of ours).
std::vector<uint16_t> mortonKeys(const std::vector<uint32_t>& cells) {
  static_assert(kCentroidGrid == 2 << kAxisBits, "a key's cell is 2x2x2 centroid cells");
  constexpr uint32_t kG = kCentroidGrid;
  std::vector<uint16_t> keys(cells.size());
  parallelFor(cells.size(), kTrianglesPerBlock / 16, [&](size_t begin, size_t end) {
    for (size_t t = begin; t < end; ++t) {
      const uint32_t c = cells[t];
      keys[t] = c == kNoCell
                    ? kNonFiniteKey
                    : uint16_t(spreadBits(c % kG >> 1) | spreadBits(c / kG % kG >> 1) << 1 |
                               spreadBits(c / kG / kG >> 1) << 2);
    }
  });
  return keys;
}

/// Where each block of kTrianglesPerBlock triangles puts its first triangle of each key:
/// [block · kBuckets + key]. Keys ascending, and within a key the blocks in order, so the
/// counting sort that follows is stable.
std::vector<size_t> firstDestinations(const std::vector<uint16_t>& keys) {
  const size_t blocks = (keys.size() + kTrianglesPerBlock - 1) / kTrianglesPerBlock;
  std::vector<size_t> first(blocks * kBuckets, 0);
  parallelForChunks(keys.size(), kTrianglesPerBlock, [&](size_t b, size_t begin, size_t end) {
    size_t* count = &first[b * kBuckets];
    for (size_t t = begin; t < end; ++t) ++count[keys[t]];
  });
  size_t sum = 0;
  for (size_t key = 0; key < kBuckets; ++key)
    for (size_t b = 0; b < blocks; ++b) sum += std::exchange(first[b * kBuckets + key], sum);
  return first;
}

/// values[from[k]] at k.
void gather(std::vector<uint32_t>& values, const std::vector<uint32_t>& from) {
  std::vector<uint32_t> moved(from.size());
  parallelFor(from.size(), kTrianglesPerBlock / 16, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) moved[k] = values[from[k]];
  });
  values.swap(moved);
}

/// Moves the triangles of `mesh` into ascending order of `keys` (one per triangle), stably.
void sortTriangles(Mesh& mesh, const std::vector<uint16_t>& keys) {
  const size_t n = mesh.triangleCount();
  std::vector<size_t> next = firstDestinations(keys);
  // One counting-sort pass: each block moves its triangles to their destinations in order.
  std::vector<uint32_t> from(n);
  LargeBuffer<uint32_t> indices;
  resizeOnHugePages(indices, 3 * n);
  parallelForChunks(n, kTrianglesPerBlock, [&](size_t b, size_t begin, size_t end) {
    size_t* at = &next[b * kBuckets];
    for (size_t t = begin; t < end; ++t) {
      const size_t k = at[keys[t]]++;
      std::copy_n(&mesh.indices[3 * t], 3, &indices[3 * k]);
      from[k] = uint32_t(t);
    }
  });
  mesh.indices.swap(indices);
  forEachFaceArray(mesh, [&](std::vector<uint32_t>& values) { gather(values, from); });
  if (mesh.sourceTriangles.empty())
    mesh.sourceTriangles = std::move(from);
  else
    gather(mesh.sourceTriangles, from);
}

}  // namespace

bool orderIfScattered(Mesh& mesh, const BuildOptions& options) {
  const size_t chunk = options.effectiveChunkTriangles();
  if (chunk == 0 || mesh.triangleCount() <= chunk) return false;
  std::vector<uint16_t> keys;
  {
    const std::vector<uint32_t> cells =
        centroidCells(mesh, mesh.indices.data(), mesh.triangleCount());
    if (chunksPerCell(cells, chunk) <= options.maxChunksPerCell) return false;
    keys = mortonKeys(cells);
  }  // the cells are freed before the sort allocates
  sortTriangles(mesh, keys);
  return true;
}

void orderTrianglesInSpace(Mesh& mesh) {
  sortTriangles(mesh, mortonKeys(centroidCells(mesh, mesh.indices.data(), mesh.triangleCount())));
}

std::vector<uint32_t> storedTriangles(const Mesh& mesh) {
  std::vector<uint32_t> stored(mesh.sourceTriangles.size());
  for (size_t t = 0; t < stored.size(); ++t) stored[mesh.sourceTriangles[t]] = uint32_t(t);
  return stored;
}

}  // namespace aperture
