#pragma once
// Scene set-up shared by render, bench, tradeoff (and batch): the scene flags, the memory
// budget, loading meshes into one render space and building the Embree scene.
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cameras/schema/params.h"
#include "core/aov/framebuffer.h"
#include "core/engine/cull.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"

namespace aperture::app {

/// One mesh of a scene: a file path or procedural spec, placed by an optional transform.
struct MeshPlacement {
  std::string spec;                         ///< file path (resolved) or "procedural:..."
  std::optional<glm::dmat4> worldFromMesh;  ///< placement; absent = identity
};

/// What a scene is made of and how it is built: the one input of the scene set-up that
/// render, bench, tradeoff, batch and Python share.
struct SceneSpec {
  std::vector<MeshPlacement> meshes;
  Placement placement = Placement::CameraRelative;
  BuildOptions build;
  bool cull = false;  ///< BVH over only the triangles the cameras may see
  /// Mesh data beyond positions that the frames read (set by withAovNeeds): the integer
  /// properties of the face./vertex. AOVs and vertex normals for shading-normal.
  std::vector<PropertyAov> properties;
  bool vertexNormals = false;
};

/// `spec` with what the AOVs of `aovs` need of the scene (vertex normals, integer properties,
/// the BVH's context filter for layered hits): the one place that derives what is
/// loaded from what is rendered (render, batch, jobs and Python call it).
SceneSpec withAovNeeds(SceneSpec spec, const AovSet& aovs);

struct SceneOptions {
  std::vector<std::string> meshes;  ///< empty: the default procedural scene
  std::string quality = "high";
  bool robust = true;  ///< --robust (the default) / --no-robust
  bool compact = false, worldSpace = false;
  long long bvhChunk = kBvhChunkTriangles;  ///< --bvh-chunk: BuildOptions::bvhChunkTriangles
  /// Leave triangles outside the cameras' view volumes out of the BVH (off by default).
  bool cull = false;
  std::string maxMemory;  ///< --max-memory: BYTES[K|M|G|T], auto, or "" for no limit
  /// What the frames compute (set by the command after parsing --aov): decides the mesh data
  /// and the BVH flags spec() asks for (withAovNeeds).
  AovSet aovs;
  LoadOptions loadOptions() const;
  BuildOptions buildOptions() const;
  /// The scene these flags describe (the procedural default scene without --mesh).
  SceneSpec spec() const;
};

/// Refuses, before anything is loaded, a job whose meshes, BVH and framebuffers (estimated
/// from the files' headers and the image size), the image codec when it writes through it
/// (kImageCodecBytes) and the direction tables of `cameras`' distorted lenses exceed
/// --max-memory. No-op without the flag.
void checkMemoryBudget(const SceneOptions& o, glm::ivec2 size, const AovSet& aovs,
                       uint64_t extraBytesPerPixel, bool imageCodec,
                       const std::vector<CameraParams>& cameras);

/// Loaded meshes and the Embree scene over them, logged as they are made.
struct LoadedScene {
  std::deque<Mesh> meshes;                ///< each distinct file once (stable addresses)
  std::vector<std::string> names;         ///< one per placement, in order
  std::vector<SceneObject> objects;       ///< what the scene is built from (subsets when culled)
  std::deque<TriangleSubset> subsets;     ///< the culled triangles, when culling
  std::optional<CullStats> cull;          ///< set when the scene was culled
  std::unique_ptr<Scene> scene;           ///< null until buildLoadedScene
  glm::dvec3 renderOrigin{0.0};           ///< world position of render space's origin
  glm::dvec3 worldLo{0.0}, worldHi{0.0};  ///< world bounds of every placement
  double loadSeconds = 0;
  size_t fileBytes = 0;
};

/// Loads the meshes: a file used once is loaded with its transform baked in and shares the
/// first placement's anchor (one render space); a file used several times is loaded once and
/// placed by instances. Computes the world bounds; builds no BVH.
LoadedScene loadSceneMeshes(const SceneSpec& spec, bool quiet);
/// Moves the triangles of each directly attached mesh that its triangle order alone keeps from
/// a chunked build under `build` into spatial order (orderIfScattered,
/// core/engine/triangle_order.h), logging what moved unless `quiet`; primIDs keep reporting the
/// loaded order. buildLoadedScene calls it first; a command that builds its own Scenes from
/// loadSceneMeshes (tradeoff) calls it once after loading.
void orderScatteredMeshes(LoadedScene& s, const BuildOptions& build, bool quiet);
/// Builds the BVH (after orderScatteredMeshes). With spec.cull, only the triangles the
/// `cameras` may see go in (Error when `cameras` is empty); a panorama among them keeps
/// everything.
void buildLoadedScene(const Device& device, LoadedScene& s, const SceneSpec& spec, bool quiet,
                      const std::vector<CameraParams>& cameras = {});
/// loadSceneMeshes then buildLoadedScene without culling.
LoadedScene loadScene(const Device& device, const SceneSpec& spec, bool quiet);
/// The scene of one mesh made from arrays (Python's Scene(positions, indices)), finished as a
/// loaded file is (finishMesh with `options`) and placed as loadSceneMeshes places a file used
/// once: its anchor is the render origin. Builds no BVH.
LoadedScene loadedSceneOfMesh(Mesh mesh, const LoadOptions& options);

/// Re-expresses the mesh's positions relative to `anchor` (offset added in double, rounded to
/// float once), so meshes loaded apart share one render space.
void moveAnchor(Mesh& m, const glm::dvec3& anchor);
/// Logs a loaded mesh (triangles, vertices, load time and speed, dropped vertices) to stderr.
void logLoadedMesh(const Mesh& m);
/// Logs what culling kept (stderr).
void logCullStats(const CullStats& c, size_t cameras);

}  // namespace aperture::app
