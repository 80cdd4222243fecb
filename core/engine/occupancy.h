#pragma once
// Where in the scene's box there is anything to hit: a coarse grid of cubic cells, a cell
// occupied when some triangle's box (grown by kSceneBoxPadding of the scene's size, as the
// scene box is) overlaps it. Built once per Scene; a camera projects its occupied cells to
// find the pixels whose rays cannot hit anything (core/engine/coverage_mask.h).
//
// Conservative by construction: every point Embree can report as a hit lies in an occupied
// cell. Triangles with a non-finite vertex are left out (Embree ignores them too).
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <optional>
#include <vector>

#include "core/engine/scene_box.h"

namespace aperture {

struct SceneObject;

/// Cells along the longest axis of the box; the others get as many as their length needs.
/// 192 against 128 and 256 (bench/RESULTS.md, "Issue 13, item 2: blocks that see nothing"):
/// finer cells fit the silhouette closer, but each frame projects more runs.
inline constexpr int kOccupancyCells = 192;
/// A scene with more placed triangles than this gets no grid (its one pass over every placed
/// triangle would cost more than the rays it saves: instances multiply the count).
inline constexpr size_t kOccupancyMaxTriangles = size_t(1) << 28;

/// Cells in a run at most: a long run seen obliquely would cover the corner of its rectangle.
inline constexpr int kOccupancyMaxRun = 8;

/// Occupied cells as runs along x: cells [x0, x1] of row (y, z).
struct OccupiedRun {
  uint16_t x0, x1, y, z;
};

struct OccupancyGrid {
  glm::dvec3 lo{0.0};  ///< render space: the grid's corner
  double cell = 0;     ///< edge of a cell, scene units
  glm::ivec3 dims{0};  ///< cells per axis, each in [1, kOccupancyCells]
  std::vector<OccupiedRun> runs;

  /// The render-space box of a run.
  SceneBox runBox(const OccupiedRun& r) const;
  /// Occupied cells in all (the runs' lengths summed).
  size_t occupiedCells() const;
};

/// Levels of occupancy: kOccupancyCells along the box's longest side, then each level's cells
/// merged kOccupancyCoarsening per axis. A frame projects every run of the levels it uses
/// (refinedCoverageMask, core/engine/coverage_mask.h), so a small image takes only coarse levels.
inline constexpr int kOccupancyLevels = 3;
inline constexpr int kOccupancyCoarsening = 3;

struct Occupancy {
  std::vector<OccupancyGrid> levels;  ///< finest first, kOccupancyLevels of them
};

/// The occupancy of `objects` (placed as a Scene places them, with render origin
/// `renderOrigin`) on `box`, the Scene's padded box; nothing when the box is degenerate or the
/// scene has more than kOccupancyMaxTriangles placed triangles. Parallel over triangles.
std::optional<Occupancy> occupancyOf(const std::vector<SceneObject>& objects,
                                     const glm::dvec3& renderOrigin, const SceneBox& box);

}  // namespace aperture
