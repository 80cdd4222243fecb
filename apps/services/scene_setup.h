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
#include "core/mesh/scene_file.h"

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
  /// Surface data the id and surface AOVs read (set by withAovNeeds; LoadOptions' fields of
  /// the same names): texture coordinates (uv, albedo), vertex colours (vertex-color, albedo),
  /// per-triangle materials (material, albedo) and OBJ objects (instance).
  bool texcoords = false, vertexColors = false, materials = false, groups = false;
  /// The albedo AOV: the materials' textures are opened for sampling (openTextureSampler)
  /// and a material whose base colour is unknown (Material::unsupported) is refused.
  bool textures = false;
  /// --gltf-scene, the job's scene.gltf_scene: the scene of every glTF file to load
  /// (LoadOptions::gltfScene); unset: each file's default scene.
  std::optional<int> gltfScene;
};

/// `spec` with what the AOVs of `aovs` need of the scene (vertex normals, integer properties,
/// texture coordinates, vertex colours, materials, OBJ groups, textures, the BVH's context
/// filter for layered hits): the one place that derives what is loaded from what is rendered
/// (render, batch, jobs and Python call it). Nothing is loaded that no AOV reads.
SceneSpec withAovNeeds(SceneSpec spec, const AovSet& aovs);

struct SceneOptions {
  std::vector<std::string> meshes;  ///< empty: the default procedural scene
  std::string quality = "high";
  bool robust = true;  ///< --robust (the default) / --no-robust
  bool compact = false, worldSpace = false;
  long long bvhChunk = kBvhChunkTriangles;  ///< --bvh-chunk: BuildOptions::bvhChunkTriangles
  std::optional<int> gltfScene;             ///< --gltf-scene: SceneSpec::gltfScene
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

/// The names behind the id AOVs, scene-wide, each list indexed by its id (ObjectIds,
/// core/engine/scene.h): the files' SceneFile::instanceNames, meshNames and materialNames
/// concatenated in placement order (a file placed twice contributes its names twice). For one
/// glTF file they are the file's nodes, meshes and materials; a PLY placement adds its stem
/// as an instance and a mesh.
struct SceneIds {
  std::vector<std::string> instance, mesh, material;
};

/// Loaded meshes and the Embree scene over them, logged as they are made.
struct LoadedScene {
  /// Each mesh finished once (stable addresses): a file's meshes that its scene places, each
  /// file once however often it is placed.
  std::deque<Mesh> meshes;
  std::vector<std::string> names;  ///< one per placement, in order
  /// What the scene is built from, in placement order and within a placement in the file's
  /// instance order (a PLY's one object per placement, as before); subsets when culled.
  std::vector<SceneObject> objects;
  SceneIds ids;  ///< the names behind the ids of `objects`
  /// The materials (by scene-wide material id) and the textures they read (re-indexed into
  /// `textures`), which buildLoadedScene sets on the Scene (SurfaceLooks; the textures'
  /// sampler only when SceneSpec::textures).
  std::vector<Material> materials;
  std::vector<SurfaceTexture> textures;   ///< empty unless SceneSpec::textures
  std::deque<TriangleSubset> subsets;     ///< the culled triangles, when culling
  std::optional<CullStats> cull;          ///< set when the scene was culled
  std::unique_ptr<Scene> scene;           ///< null until buildLoadedScene
  glm::dvec3 renderOrigin{0.0};           ///< world position of render space's origin
  glm::dvec3 worldLo{0.0}, worldHi{0.0};  ///< world bounds of every placement
  double loadSeconds = 0;
  size_t fileBytes = 0;
};

/// Loads the meshes of every placement through loadSceneFile: each of a file's MeshInstances
/// becomes a SceneObject placed at placement · MeshInstance::worldFromMesh. A mesh placed once
/// overall (its file placed once and the mesh used by one of its instances) is finished with
/// that whole transform baked in (in double) and shares the first object's anchor (one render
/// space); a mesh placed several times (a glTF mesh used by several nodes, a file placed
/// several times) is finished untransformed once and placed by Embree instances (its memory
/// once). Ids are numbered scene-wide (SceneIds); a file whose primitives were skipped warns
/// once. Computes the world bounds; builds no BVH.
LoadedScene loadSceneMeshes(const SceneSpec& spec, bool quiet);
/// Moves the triangles of each directly attached mesh that its triangle order alone keeps from
/// a chunked build under `build` into spatial order (orderIfScattered,
/// core/engine/triangle_order.h), logging what moved unless `quiet`; primIDs keep reporting the
/// loaded order. buildLoadedScene calls it first; a command that builds its own Scenes from
/// loadSceneMeshes (tradeoff) calls it once after loading.
void orderScatteredMeshes(LoadedScene& s, const BuildOptions& build, bool quiet);
/// Builds the BVH (after orderScatteredMeshes) and sets the scene's SurfaceLooks (the
/// materials; with spec.textures their textures' sampler, core/io/texture_sampler.h). With
/// spec.cull, only the triangles the `cameras` may see go in (Error when `cameras` is
/// empty); a panorama among them keeps everything.
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
