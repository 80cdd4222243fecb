// The occupancy grid (core/engine/occupancy.h) the coverage mask is built from: every placed
// triangle, directly attached or instanced, lies in occupied cells at every level, and empty
// space is not occupied.
#include <gtest/gtest.h>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <vector>

#include "core/engine/occupancy.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "tests/numerics_support.h"

namespace aperture {
namespace occupancy_test {

/// The mesh placed once as loaded and once turned and moved (an Embree instance).
std::vector<SceneObject> placedTwice(const Mesh& mesh) {
  return test::placedTwice(mesh, {40.0, -5.0, 12.0});
}

/// Whether the render-space point `p` lies in a run's box of `grid`.
bool inOccupiedCell(const OccupancyGrid& grid, const glm::dvec3& p) {
  for (const OccupiedRun& r : grid.runs) {
    const SceneBox b = grid.runBox(r);
    if (glm::all(glm::lessThanEqual(glm::dvec3(b.lo), p)) &&
        glm::all(glm::lessThanEqual(p, glm::dvec3(b.hi))))
      return true;
  }
  return false;
}

TEST(Occupancy, EveryPlacedTriangleLiesInOccupiedCellsAndEmptySpaceIsNotOccupied) {
  const Mesh mesh = loadMesh("procedural:spheres?tris=3000");
  const std::vector<SceneObject> objects = placedTwice(mesh);
  const Scene scene(test::numericsDevice(), objects);
  const Occupancy* occupancy = scene.occupancy();
  ASSERT_NE(occupancy, nullptr);
  ASSERT_EQ(occupancy->levels.size(), size_t(kOccupancyLevels));
  const OccupancyGrid* grid = &occupancy->levels.front();
  EXPECT_EQ(std::max({grid->dims.x, grid->dims.y, grid->dims.z}), kOccupancyCells);
  for (size_t level = 0; level < occupancy->levels.size(); ++level)
    for (const SceneObject& o : objects) {
      const glm::dmat4 renderFromLocal = glm::translate(glm::dmat4(1.0), -scene.renderOrigin()) *
                                         o.worldFromMesh *
                                         glm::translate(glm::dmat4(1.0), o.mesh->anchor);
      for (size_t t = 0; t < mesh.triangleCount(); t += 7) {
        glm::dvec3 corner[3];
        for (int c = 0; c < 3; ++c)
          corner[c] = glm::dvec3(renderFromLocal *
                                 glm::dvec4(glm::dvec3(mesh.vertex(mesh.indices[3 * t + c])), 1.0));
        // The corners and points inside the triangle.
        for (const glm::dvec3& b : {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1),
                                    glm::dvec3(1.0 / 3), glm::dvec3(0.6, 0.3, 0.1)})
          ASSERT_TRUE(inOccupiedCell(occupancy->levels[level],
                                     b.x * corner[0] + b.y * corner[1] + b.z * corner[2]))
              << "level " << level << " triangle " << t;
      }
    }
  // Each level's cells are kOccupancyCoarsening of the finer one's per axis, and it has fewer
  // runs.
  for (size_t level = 1; level < occupancy->levels.size(); ++level) {
    const OccupancyGrid &coarse = occupancy->levels[level], &fine = occupancy->levels[level - 1];
    EXPECT_EQ(coarse.cell, fine.cell * kOccupancyCoarsening) << level;
    EXPECT_LT(coarse.runs.size(), fine.runs.size()) << level;
  }
  // The spheres fill a small part of their box: most cells are empty, and the corner of the
  // box far from both placements is.
  const size_t cells = size_t(grid->dims.x) * size_t(grid->dims.y) * size_t(grid->dims.z);
  EXPECT_LT(grid->occupiedCells(), cells / 4);
  EXPECT_GT(grid->occupiedCells(), 100u);
}

}  // namespace occupancy_test
}  // namespace aperture
