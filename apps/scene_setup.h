#pragma once
// Scene set-up shared by render, bench, tradeoff (and batch): the scene flags, the memory
// budget, loading meshes into one render space and building the Embree scene.
#include <CLI/CLI.hpp>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cameras/params.h"
#include "core/cull.h"
#include "core/framebuffer.h"
#include "core/mesh.h"
#include "core/scene.h"

namespace aperture::app {

struct SceneOptions {
  std::vector<std::string> meshes;  ///< empty: the default procedural scene
  std::string quality = "high";
  bool robust = false, compact = false, worldSpace = false;
  /// Leave triangles outside the cameras' view volumes out of the BVH (off by default).
  bool cull = false;
  std::string maxMemory;  ///< --max-memory: BYTES[K|M|G|T], auto, or "" for no limit
  LoadOptions loadOptions() const;
  BuildOptions buildOptions() const;
};

void addSceneOptions(CLI::App& app, SceneOptions& o);

/// Refuses, before anything is loaded, a job whose meshes, BVH and framebuffers (estimated
/// from the files' headers and the image size) exceed --max-memory. No-op without the flag.
void checkMemoryBudget(const SceneOptions& o, glm::ivec2 size, AovMask aovs,
                       uint64_t extraBytesPerPixel = 0);

/// Loaded meshes + Embree scene, logged as they are made.
struct LoadedScene {
  std::vector<Mesh> meshes;
  std::vector<SceneObject> objects;    ///< what the scene is built from (subsets when culled)
  std::deque<TriangleSubset> subsets;  ///< the culled triangles, when culling
  std::optional<CullStats> cull;       ///< set when the scene was culled
  std::unique_ptr<Scene> scene;
  glm::dvec3 worldLo{0.0}, worldHi{0.0};
  double loadSeconds = 0;
  size_t fileBytes = 0;
};
std::vector<Mesh> loadMeshes(const SceneOptions& o, bool quiet);
/// Re-expresses the mesh's positions relative to `anchor` (offset added in double, rounded to
/// float once), so meshes loaded apart share one render space.
void moveAnchor(Mesh& m, const glm::dvec3& anchor);
/// Logs a loaded mesh (triangles, vertices, load time and speed, dropped vertices) to stderr.
void logLoadedMesh(const Mesh& m);
/// Loads the meshes and their world bounds (no BVH yet: scene stays null).
LoadedScene loadSceneMeshes(const SceneOptions& o, bool quiet);
/// Builds the BVH of loaded meshes. With o.cull, only the triangles the `cameras` may see go
/// in (Error when o.cull is set and `cameras` is empty); panoramas keep everything.
void buildLoadedScene(const Device& device, LoadedScene& s, const SceneOptions& o, bool quiet,
                      const std::vector<CameraParams>& cameras = {});
/// Logs what culling kept (stderr).
void logCullStats(const CullStats& c, size_t cameras);
/// loadSceneMeshes then buildLoadedScene without culling.
LoadedScene loadScene(const Device& device, const SceneOptions& o, bool quiet);

}  // namespace aperture::app
