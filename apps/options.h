#pragma once
// Option groups shared by the subcommands (render, bench, camera), with their validation.
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
#include "core/render.h"
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

/// Camera flags as text, converted by toParams() with errors that name the flag and value.
struct CameraOptions {
  std::string type = "perspective", eye, at, dir, up = "0,1,0", viewport, sensor, fovAxis = "y";
  std::string shift, obliqueDir, obliqueAngles, lon, lat;
  double fov = 0, d = 0, focalLength = 0, aperture = 0, focus = 0, fisheyeFov = 180;
  bool architectural = false;
  std::string size = "960,540";
  int spp = 1;
  /// Builds the parameters; with no --eye the camera frames the scene's bounds (world space).
  CameraParams toParams(const glm::dvec3& worldLo, const glm::dvec3& worldHi) const;
};

struct RenderOptions {
  std::string aovs = "color,depth";
  int packet = 16, tile = 32, threads = 0;
  RenderSettings settings(int spp) const;
};

void addSceneOptions(CLI::App& app, SceneOptions& o);
void addCameraOptions(CLI::App& app, CameraOptions& o);
void addRenderOptions(CLI::App& app, RenderOptions& o);

/// Parses and bounds-checks --size: each side in [1, 65536], at most 2^28 pixels.
glm::ivec2 parseImageSize(const std::string& size);

/// Refuses, before anything is loaded, a job whose meshes, BVH and framebuffers (estimated
/// from the files' headers and the image size) exceed --max-memory. No-op without the flag.
void checkMemoryBudget(const SceneOptions& o, glm::ivec2 size, AovMask aovs,
                       uint64_t extraBytesPerPixel = 0);

/// Parses "X,Y,Z" / "A,B" for `flag`; throws Error("--eye: expected X,Y,Z ...").
glm::dvec3 parseVec3(const std::string& flag, const std::string& text);
glm::dvec2 parseVec2(const std::string& flag, const std::string& text);

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

/// A --preset: settings picked from the measured speed/accuracy frontier (bench/TRADEOFF.md).
struct Preset {
  const char* name;
  const char* bvhQuality;
  bool robust;
  int spp;
  bool halfColor;
  const char* compression;
};
/// fast, balanced or exact; throws Error listing the names for anything else.
const Preset& findPreset(const std::string& name);
void addPresetOption(CLI::App& app, std::string& preset);
/// Sets every knob of the preset that the command line did not give explicitly (`sub` is the
/// parsed subcommand); half/compression may be null where the command writes no EXR.
void applyPreset(const std::string& name, const CLI::App& sub, SceneOptions& scene,
                 CameraOptions& camera, bool* halfColor, std::string* compression);

/// Limits TBB (and so Embree's builder) to n threads while alive; n = 0 keeps all cores.
class ThreadLimit {
 public:
  explicit ThreadLimit(int n);
  ~ThreadLimit();
  int threads() const { return threads_; }

 private:
  std::unique_ptr<struct ThreadLimitImpl> impl_;
  int threads_;
};

}  // namespace aperture::app
