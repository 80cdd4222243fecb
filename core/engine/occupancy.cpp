#include "core/engine/occupancy.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "core/engine/scene.h"
#include "core/util/parallel.h"

namespace aperture {

SceneBox OccupancyGrid::runBox(const OccupiedRun& r) const {
  const glm::dvec3 lo3 = lo + cell * glm::dvec3(r.x0, r.y, r.z);
  const glm::dvec3 hi3 = lo + cell * glm::dvec3(r.x1 + 1, r.y + 1, r.z + 1);
  return {glm::vec3(lo3), glm::vec3(hi3)};
}

size_t OccupancyGrid::occupiedCells() const {
  size_t n = 0;
  for (const OccupiedRun& r : runs) n += size_t(r.x1 - r.x0 + 1);
  return n;
}

namespace {

/// Cells of `grid` marked occupied (one byte each, x fastest), written with relaxed atomic
/// stores: several triangles may mark one cell at once.
class CellMarks {
 public:
  explicit CellMarks(const OccupancyGrid& grid)
      : grid_(grid), marks_(size_t(grid.dims.x) * size_t(grid.dims.y) * size_t(grid.dims.z), 0) {}

  /// Marks every cell the render-space box [lo, hi] overlaps.
  void markBox(const glm::dvec3& lo, const glm::dvec3& hi) {
    glm::ivec3 first, last;
    for (int a = 0; a < 3; ++a) {
      first[a] = cellIndex(lo[a], a);
      last[a] = cellIndex(hi[a], a);
    }
    for (int z = first.z; z <= last.z; ++z)
      for (int y = first.y; y <= last.y; ++y)
        for (int x = first.x; x <= last.x; ++x)
          __atomic_store_n(&marks_[index(x, y, z)], uint8_t(1), __ATOMIC_RELAXED);
  }

  /// The marks of `coarse` (the cells of this grid merged kOccupancyCoarsening per axis): a
  /// coarse cell is marked when one of its cells is.
  CellMarks coarsened(const OccupancyGrid& coarse) const {
    CellMarks out(coarse);
    for (int z = 0; z < grid_.dims.z; ++z)
      for (int y = 0; y < grid_.dims.y; ++y)
        for (int x = 0; x < grid_.dims.x; ++x)
          if (marks_[index(x, y, z)])
            out.marks_[out.index(x / kOccupancyCoarsening, y / kOccupancyCoarsening,
                                 z / kOccupancyCoarsening)] = 1;
    return out;
  }

  /// The marked cells as runs along x.
  std::vector<OccupiedRun> runs() const {
    std::vector<OccupiedRun> out;
    for (int z = 0; z < grid_.dims.z; ++z)
      for (int y = 0; y < grid_.dims.y; ++y)
        for (int x = 0; x < grid_.dims.x; ++x) {
          if (!marks_[index(x, y, z)]) continue;
          const int x0 = x;
          while (x + 1 < grid_.dims.x && x + 1 - x0 < kOccupancyMaxRun &&
                 marks_[index(x + 1, y, z)])
            ++x;
          out.push_back({uint16_t(x0), uint16_t(x), uint16_t(y), uint16_t(z)});
        }
    return out;
  }

 private:
  int cellIndex(double p, int axis) const {
    const double c = std::floor((p - grid_.lo[axis]) / grid_.cell);
    return int(std::clamp(c, 0.0, double(grid_.dims[axis] - 1)));
  }
  size_t index(int x, int y, int z) const {
    return (size_t(z) * size_t(grid_.dims.y) + size_t(y)) * size_t(grid_.dims.x) + size_t(x);
  }

  OccupancyGrid grid_;  /// its geometry (no runs)
  std::vector<uint8_t> marks_;
};

/// Marks the cells of the triangles of one placed object, its vertices taken to render space
/// by `renderFromLocal` (the identity for an object Embree holds as stored), each triangle's
/// box grown by `pad`.
void markObject(CellMarks& marks, const Mesh& m, const LargeBuffer<uint32_t>& indices,
                const glm::dmat4& renderFromLocal, double pad) {
  const bool identity = renderFromLocal == glm::dmat4(1.0);
  const float* p = m.positions.data();
  const size_t triangles = indices.size() / 3;
  parallelFor(triangles, 4096, [&](size_t first, size_t last) {
    for (size_t t = first; t != last; ++t) {
      glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
      bool finite = true;
      for (int c = 0; c < 3; ++c) {
        const float* v = p + 3 * size_t(indices[3 * t + size_t(c)]);
        glm::dvec3 q(v[0], v[1], v[2]);
        if (!identity) q = glm::dvec3(renderFromLocal * glm::dvec4(q, 1.0));
        finite = finite && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
      }
      if (finite) marks.markBox(lo - pad, hi + pad);
    }
  });
}

}  // namespace

std::optional<Occupancy> occupancyOf(const std::vector<SceneObject>& objects,
                                     const glm::dvec3& renderOrigin, const SceneBox& box) {
  size_t placed = 0;
  for (const SceneObject& o : objects)
    placed += o.subset ? o.subset->triangleCount() : o.mesh->triangleCount();
  if (placed > kOccupancyMaxTriangles) return std::nullopt;
  OccupancyGrid grid;
  const glm::dvec3 lo(box.lo), hi(box.hi), extent = hi - lo;
  grid.lo = lo;
  grid.cell = std::max({extent.x, extent.y, extent.z}) / kOccupancyCells;
  if (!(grid.cell > 0) || !std::isfinite(grid.cell)) return std::nullopt;
  for (int a = 0; a < 3; ++a)
    grid.dims[a] = std::clamp(int(std::ceil(extent[a] / grid.cell)), 1, kOccupancyCells);
  // As the scene box's padding: covers the rounding of the vertices, of an instance's float
  // matrix and of the hits Embree reports.
  const glm::dvec3 magnitude = glm::max(glm::abs(lo), glm::abs(hi));
  const double pad = double(kSceneBoxPadding) * std::max({extent.x, extent.y, extent.z, magnitude.x,
                                                          magnitude.y, magnitude.z});
  Occupancy occupancy;
  CellMarks marks(grid);
  for (const SceneObject& o : objects) {
    const Mesh& m = *o.mesh;
    const LargeBuffer<uint32_t>& indices = o.subset ? o.subset->indices : m.indices;
    const glm::dmat4 renderFromLocal = glm::translate(glm::dmat4(1.0), -renderOrigin) *
                                       o.worldFromMesh * glm::translate(glm::dmat4(1.0), m.anchor);
    markObject(marks, m, indices, renderFromLocal, pad);
  }
  for (int level = 0; level < kOccupancyLevels; ++level) {
    if (level > 0) {
      const OccupancyGrid& finer = occupancy.levels.back();
      grid = OccupancyGrid{finer.lo,
                           finer.cell * kOccupancyCoarsening,
                           (finer.dims + kOccupancyCoarsening - 1) / kOccupancyCoarsening,
                           {}};
      marks = marks.coarsened(grid);
    }
    grid.runs = marks.runs();
    occupancy.levels.push_back(std::move(grid));
  }
  return occupancy;
}

}  // namespace aperture
