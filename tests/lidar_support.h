#pragma once
// Helpers of the LiDAR tests (tests/cameras/lidar/): a closed box room built by hand, its
// analytic ray distances, and small sensor specs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <limits>
#include <memory>
#include <string>

#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture::test {

/// The current test's scratch directory (test::scratchDir), made once per test so that files
/// written one after another stay together.
inline std::string lidarScratchDir() {
  static std::string test, dir;
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string name =
      info ? std::string(info->test_suite_name()) + "." + info->name() : std::string("misc");
  if (name != test || dir.empty()) {
    test = name;
    dir = scratchDir();
  }
  return dir;
}

/// Writes `text` to `name` in lidarScratchDir() and returns its path.
inline std::string writeScratchFile(const std::string& name, const std::string& text) {
  const std::string path = lidarScratchDir() + "/" + name;
  writeFile(path, text);
  return path;
}

/// A closed box room [−h.x, h.x] × [−h.y, h.y] × [−h.z, h.z] (metres) offset by `centre`: 12
/// triangles, and the scene over it.
struct BoxRoom {
  glm::dvec3 centre{0.0};
  glm::dvec3 half{5.0, 4.0, 3.0};
  std::unique_ptr<Mesh> mesh;
  std::unique_ptr<Scene> scene;
};

inline BoxRoom makeBoxRoom(const glm::dvec3& half, const glm::dvec3& centre = glm::dvec3(0.0)) {
  BoxRoom room;
  room.centre = centre;
  room.half = half;
  std::string obj;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 v = centre + glm::dvec3((k & 1) ? half.x : -half.x, (k & 2) ? half.y : -half.y,
                                             (k & 4) ? half.z : -half.z);
    char line[128];
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", v.x, v.y, v.z);
    obj += line;
  }
  // Faces by corner index (1-based): -x, +x, -y, +y, -z, +z, two triangles each.
  obj +=
      "f 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\n"
      "f 1 5 6\nf 1 6 2\nf 3 4 8\nf 3 8 7\n"
      "f 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\n";
  room.mesh = std::make_unique<Mesh>(loadObjFromMemory(obj.data(), obj.size(), "box room"));
  finishMesh(*room.mesh, LoadOptions{});
  room.scene = std::make_unique<Scene>(numericsDevice(), std::vector<const Mesh*>{room.mesh.get()});
  return room;
}

/// Distance from `origin` (inside the box) along unit `dir` to the box's wall: the least
/// positive exit distance over the three slabs, in double.
inline double boxExitDistance(const BoxRoom& room, const glm::dvec3& origin,
                              const glm::dvec3& dir) {
  double t = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0) continue;
    const double wall = room.centre[a] + (dir[a] > 0 ? room.half[a] : -room.half[a]);
    t = std::min(t, (wall - origin[a]) / dir[a]);
  }
  return t;
}

/// Whether world point p lies on the box's surface within `tol` metres.
inline bool onBoxWall(const BoxRoom& room, const glm::dvec3& p, double tol) {
  double outside = 0, nearest = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double d = std::fabs(p[a] - room.centre[a]) - room.half[a];
    outside = std::max(outside, d);
    nearest = std::min(nearest, std::fabs(d));
  }
  return outside <= tol && nearest <= tol;
}

}  // namespace aperture::test
