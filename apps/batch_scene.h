#pragma once
// `aperture batch`: the job's scene, each mesh file loaded once and the BVH built once.
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "apps/job.h"
#include "core/mesh.h"
#include "core/scene.h"

namespace aperture::app {

/// The job's meshes, each file loaded once, and the Embree scene over their placements.
struct BatchScene {
  std::deque<Mesh> meshes;
  std::deque<TriangleSubset> subsets;  ///< with performance.cull
  std::vector<std::string> names;      ///< one per job mesh entry
  std::unique_ptr<Scene> scene;
  double loadSeconds = 0;
};

/// Loads the meshes and builds the scene. A file used once is loaded with its transform baked
/// in; a file used several times is loaded once and placed by instances. `cameras`: the
/// images this run renders (with performance.cull, the BVH keeps what they may see). Logs the
/// meshes, culling and BVH on stderr unless `quiet`.
BatchScene buildBatchScene(const Device& device, const Job& job, bool quiet,
                           const std::vector<CameraParams>& cameras);

}  // namespace aperture::app
