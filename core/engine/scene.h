#pragma once
// The Embree device and scene (BVH) built over loaded meshes.
#include <embree3/rtcore.h>

#include <cstddef>
#include <glm/glm.hpp>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/engine/occupancy.h"
#include "core/engine/scene_box.h"
#include "core/mesh/mesh.h"
#include "core/mesh/scene_file.h"

namespace aperture {

/// One Embree device for the process; its error callback turns Embree errors into Error
/// exceptions (thrown from the next checked call), and a memory monitor tracks Embree's bytes.
class Device {
 public:
  /// `config` is passed to rtcNewDevice (e.g. "threads=2"); when empty, the environment
  /// variable APERTURE_EMBREE_CONFIG if set, else Embree's defaults.
  explicit Device(const std::string& config = "");
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  RTCDevice handle() const { return device_; }
  /// Throws Error if Embree reported an error since the last call.
  void check(const char* what) const;
  /// Bytes Embree currently holds (from its memory monitor callback).
  long long memoryBytes() const;
  /// The ISA Embree chose for this CPU ("AVX512", "AVX2", ...), from rtcGetDeviceProperty.
  std::string isaName() const;

  struct State;

 private:
  RTCDevice device_ = nullptr;
  std::unique_ptr<State> state_;
};

enum class BvhQuality { Low, Medium, High };
BvhQuality parseBvhQuality(const std::string& name);  ///< "low|medium|high", else Error
const char* bvhQualityName(BvhQuality q);

/// Default of BuildOptions::bvhChunkTriangles: 2^24 triangles, so a 10^8-triangle mesh is
/// built as 6 BVHs and its build peaks at 90 bytes per triangle instead of 117
/// (bench/RESULTS.md, "Issue 13, item 3: large meshes built in chunks").
inline constexpr size_t kBvhChunkTriangles = size_t(1) << 24;

/// Default of BuildOptions::maxChunksPerCell. Chunks pay only where they keep to their own part
/// of space. The procedural spheres' consecutive triangles are neighbours (1.00-1.01 chunks
/// per cell; 1e8 triangles in 6 chunks traced 1-10 % slower than one BVH); the shared scans
/// and scenes are ordered by scan, part or material and are not (in 3 chunks: the dragon 1.05
/// and 5-12 % slower, the bathroom 1.10 and 30 %, the crown 1.15 and 30 %). A mesh written
/// region by region (a tiled export) would pass; none of the shared meshes is one.
inline constexpr double kMaxChunksPerCell = 1.03;

/// The smallest BuildOptions::bvhChunkTriangles the command line and job files accept, 0 aside:
/// each chunk is a sub-scene and an instance, so tiny chunks would trade the BVH for overhead.
inline constexpr size_t kMinBvhChunkTriangles = 1024;
/// `triangles` as a BuildOptions::bvhChunkTriangles; throws Error naming `where` (the flag or
/// job key) unless it is 0 or in [kMinBvhChunkTriangles, 2^32].
size_t checkedBvhChunkTriangles(long long triangles, const std::string& where);

struct BuildOptions {
  BvhQuality quality = BvhQuality::High;
  /// RTC_SCENE_FLAG_ROBUST: watertight traversal, on by default (issue 15): without it a few
  /// rays in ten million slip through the shared edges of a closed mesh; it costs 0-8 % of
  /// trace time (bench/TRADEOFF.md). Off only when asked for (--no-robust, preset fast).
  bool robust = true;
  bool compact = false;  ///< RTC_SCENE_FLAG_COMPACT: less memory, slower traversal
  /// RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION on the scene and every instanced sub-scene: lets
  /// layered hits (core/engine/layers.h) collect every hit along a ray through a filter function in
  /// the intersection context. Off unless layers are asked for: Embree then selects its
  /// filter-capable traversal kernels for every ray of the scene.
  bool contextFilter = false;
  /// A directly attached object with more triangles than this is built as several BVHs of at
  /// most this many consecutive triangles each, one after the other, each placed by an
  /// identity instance. Embree holds 32 bytes of primitive references per triangle of the BVH
  /// it is building until that build ends; in chunks only one chunk's are held at a time. 0:
  /// never. Not used with `compact`, whose build holds no such array beside its BVH, nor for
  /// a mesh whose triangle order is scattered in space (maxChunksPerCell).
  size_t bvhChunkTriangles = kBvhChunkTriangles;
  /// A mesh is built in chunks only when its chunksPerCell is at most this: otherwise rays
  /// would descend several chunks' BVHs where one would do, and it is built as one BVH.
  double maxChunksPerCell = kMaxChunksPerCell;
  /// The chunk size that applies under these options (0: none).
  size_t effectiveChunkTriangles() const { return compact ? 0 : bvhChunkTriangles; }
};

struct BuildStats {
  size_t triangles = 0;        ///< triangles as placed (an instanced mesh counts each time)
  size_t culledTriangles = 0;  ///< triangles as placed that a TriangleSubset left out
  size_t uniqueTriangles = 0;  ///< triangles stored (each mesh once)
  double buildSeconds = 0;     ///< rtcCommitScene wall time
  long long embreeBytes = 0;   ///< Embree's memory after the build
  size_t chunks = 0;           ///< BVHs built for chunked objects (BuildOptions::bvhChunkTriangles)
  /// The largest chunksPerCell of the objects large enough to chunk (0 when none was).
  double chunksPerCell = 0;
};

/// Cells per axis of the grid on a mesh's box that centroidCells and chunksPerCell use.
inline constexpr int kCentroidGrid = 64;
/// centroidCells' value for a triangle whose centroid is not finite.
inline constexpr uint32_t kNoCell = 0xFFFFFFFFu;
/// For each of the `triangles` triangles of `m` (from `indices`), the cell of a
/// kCentroidGrid³ grid on the mesh's box that holds its centroid, (z · 64 + y) · 64 + x, or
/// kNoCell.
std::vector<uint32_t> centroidCells(const Mesh& m, const uint32_t* indices, size_t triangles);
/// How far the runs of `chunkTriangles` consecutive triangles share space, from their
/// centroidCells: over the cells that hold a centroid, the mean number of runs with a centroid
/// in the cell. 1 when every run keeps to its own cells, up to the number of runs when they
/// are interleaved everywhere.
double chunksPerCell(const std::vector<uint32_t>& cells, size_t chunkTriangles);
/// chunksPerCell of the centroidCells of `m`'s `triangles` triangles from `indices`.
double chunksPerCell(const Mesh& m, const uint32_t* indices, size_t triangles,
                     size_t chunkTriangles);

/// Some of a mesh's triangles (for view-volume culling, core/engine/cull.h): the kept triangles'
/// vertex indices in their original order, and the original index of each kept triangle.
struct TriangleSubset {
  LargeBuffer<uint32_t> indices;  ///< 3 per kept triangle, into the mesh's vertex buffer
  std::vector<uint32_t> primIds;  ///< primIds[k] = the mesh's index of kept triangle k
  size_t triangleCount() const { return primIds.size(); }
};

/// What the id AOVs report for a hit on an object, numbered scene-wide by the scene set-up
/// (apps/services/scene_setup): instance = `instance` (plus the mesh's faceGroups[t] where it
/// has them), mesh = `mesh`, material = `materialBase` (plus the mesh's faceMaterials[t]).
struct ObjectIds {
  uint32_t instance = 0, mesh = 0, materialBase = 0;

  /// The instance id of stored triangle `t` of the object's mesh, whose faceGroups are
  /// `groups` (null when it has none).
  uint32_t instanceOfTriangle(const uint32_t* groups, uint32_t t) const {
    return instance + (groups ? groups[t] : 0u);
  }
  uint32_t instanceOfTriangle(const std::vector<uint32_t>& groups, uint32_t t) const {
    return instanceOfTriangle(groups.empty() ? nullptr : groups.data(), t);
  }
};

/// One placement of a mesh: world = worldFromMesh · (mesh.anchor + position).
struct SceneObject {
  SceneObject() = default;
  explicit SceneObject(const Mesh* mesh_) : mesh(mesh_) {}
  SceneObject(const Mesh* mesh_, const glm::dmat4& worldFromMesh_,  // NOLINT: {mesh, placement}
              const TriangleSubset* subset_ = nullptr, const ObjectIds& ids_ = {})
      : mesh(mesh_), worldFromMesh(worldFromMesh_), subset(subset_), ids(ids_) {}

  const Mesh* mesh = nullptr;
  glm::dmat4 worldFromMesh{1.0};
  /// Optional: only these triangles go into the BVH (they share the mesh's vertex buffer;
  /// must outlive the Scene). Objects placing the same mesh must give the same subset.
  const TriangleSubset* subset = nullptr;
  ObjectIds ids;
};

/// The render origin of a Scene over `objects` (not empty): the first object's anchor, placed
/// in world space.
glm::dvec3 renderOriginOf(const std::vector<SceneObject>& objects);

/// For each object, whether a Scene over `objects` attaches it directly rather than through an
/// instance: its mesh is placed once, untransformed, and its anchor is the render origin
/// (renderOriginOf). Only such objects are built in chunks.
std::vector<bool> attachedDirectly(const std::vector<SceneObject>& objects);

/// An Embree scene over meshes that outlive it (their vertex and index buffers are shared
/// with Embree, not copied). Object k gets top-level geomID k. An object whose mesh appears
/// once, untransformed, with the render origin as its anchor is attached directly; a mesh
/// placed several times (or transformed) is built once as a sub-scene and placed by Embree
/// instances. A directly attached object larger than BuildOptions::bvhChunkTriangles is built
/// as chunks, each its own sub-scene under an identity instance; every trace goes through
/// intersectScene (core/engine/intersect_scene.h), which reports its hits as those of the object.
/// The render origin is the first object's anchor.
class Scene {
 public:
  Scene(const Device& device, const std::vector<SceneObject>& objects,
        const BuildOptions& options = {});
  /// Each mesh once, untransformed; all must share one anchor.
  Scene(const Device& device, const std::vector<const Mesh*>& meshes,
        const BuildOptions& options = {});
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  RTCScene handle() const { return scene_; }
  const BuildStats& stats() const { return stats_; }
  const BuildOptions& options() const { return options_; }
  /// World position of render-space origin (the meshes' shared anchor), double precision.
  const glm::dvec3& renderOrigin() const { return renderOrigin_; }
  /// Number of objects placed by an Embree instance (0 when nothing repeats).
  size_t instanceCount() const { return instanced_; }
  /// World-space normal of an instanced hit: Embree reports Ng in the mesh's space.
  /// Indexed by the top-level geomID (hit.instID[0]).
  const glm::mat3& normalFromMesh(unsigned object) const { return normalFromMesh_[object]; }
  /// The mesh of object `object` (the top-level geomID, or the instance's): its properties
  /// and vertex normals, indexed by meshTriangle().
  const Mesh& objectMesh(unsigned object) const { return *objectMeshes_[object]; }
  /// The ids of object `object` (the top-level geomID, or the instance's).
  const ObjectIds& objectIds(unsigned object) const { return objects_[object].ids; }
  /// The materials and textures the albedo AOV reads (set by the scene set-up); null when
  /// none were given.
  const SurfaceLooks* looks() const { return looks_.get(); }
  void setLooks(std::shared_ptr<const SurfaceLooks> looks) { looks_ = std::move(looks); }
  /// Number of objects (top-level geomIDs 0 .. objectCount() - 1).
  size_t objectCount() const { return objectMeshes_.size(); }
  /// The objects as given (object k is top-level geomID k): their meshes and placements, for
  /// queries that read the triangles themselves (core/queries: closest points, winding numbers).
  const std::vector<SceneObject>& objects() const { return objects_; }
  /// Render-space box that holds everything a ray can hit, padded (core/engine/scene_box.h);
  /// nullopt when Embree's bounds are empty or not finite.
  const std::optional<SceneBox>& box() const { return box_; }
  /// Where in the box there is anything to hit (core/engine/occupancy.h), built at the first call
  /// (thread-safe: cameras that cannot use it never pay for it); null without a box or
  /// above kOccupancyMaxTriangles placed triangles.
  const Occupancy* occupancy() const;
  /// True when some object was built from a TriangleSubset (view-volume culling).
  bool culled() const { return !primIdMaps_.empty(); }
  /// True when Embree's primID is not what the user numbers a triangle by: some object was
  /// culled (primID indexes its subset), or its mesh's triangles were moved by
  /// orderTrianglesInSpace (core/engine/triangle_order.h). Then outputs go through sourcePrimId().
  bool remapsPrimIds() const { return culled() || reordered_; }
  /// The stored triangle of object `object`'s mesh (an index into its buffers) that Embree's
  /// primID `prim` on that object (the top-level geomID, or the instance's) stands for.
  uint32_t meshTriangle(unsigned object, uint32_t prim) const {
    const uint32_t* map = primIdMaps_.empty() ? nullptr : primIdMaps_[object];
    return map ? map[prim] : prim;
  }
  /// The primID to report for Embree's primID `prim` on object `object`: the triangle's index
  /// in the order its mesh was loaded in.
  uint32_t sourcePrimId(unsigned object, uint32_t prim) const {
    return objectMeshes_[object]->sourceTriangle(meshTriangle(object, prim));
  }
  /// True when some object was built in chunks: Embree then reports its hits through the
  /// chunks' instances, and resolveChunkHits must run on every hit before anything reads it.
  bool hasChunks() const { return !chunkSlots_.empty(); }
  /// Turns the `n` hits reported through a chunk's instance into what Embree reports for the
  /// object attached directly: geomID the object, primID counted from the object's first
  /// triangle, instID RTC_INVALID_GEOMETRY_ID. Other hits and misses are left as they are.
  void resolveChunkHits(unsigned* geomID, unsigned* primID, unsigned* instID, size_t n) const;

 private:
  const Device& device_;
  RTCScene scene_ = nullptr;
  BuildOptions options_;
  BuildStats stats_;
  glm::dvec3 renderOrigin_{0.0};
  size_t instanced_ = 0;
  std::vector<glm::mat3> normalFromMesh_;
  std::vector<const Mesh*> objectMeshes_;    ///< per object
  std::vector<const uint32_t*> primIdMaps_;  ///< per object; empty when nothing is culled
  bool reordered_ = false;                   ///< some object's mesh has Mesh::sourceTriangles
  std::optional<SceneBox> box_;
  std::shared_ptr<const SurfaceLooks> looks_;
  std::vector<SceneObject> objects_;  ///< as given: occupancy() reads their triangles
  mutable std::once_flag occupancyOnce_;
  mutable std::optional<Occupancy> occupancy_;
  std::vector<RTCScene> subScenes_;
  /// What a top-level geomID placing a chunk stands for: the chunk's object
  /// (RTC_INVALID_GEOMETRY_ID for a geomID that places no chunk) and its first triangle.
  struct ChunkSlot {
    unsigned object = RTC_INVALID_GEOMETRY_ID;
    uint32_t firstPrim = 0;
  };
  std::vector<ChunkSlot> chunkSlots_;  ///< per top-level geomID; empty when nothing is chunked

  /// A sub-scene (owned by subScenes_) of one triangle geometry over `triangles` triangles of
  /// `m` from `indices`, committed; `what` names it in an Embree error.
  RTCScene buildSubScene(const Mesh& m, const uint32_t* indices, size_t triangles,
                         RTCBuildQuality quality, RTCSceneFlags flags, const std::string& what);

  void attachChunks(unsigned object, const Mesh& m, const LargeBuffer<uint32_t>& indices,
                    size_t chunkTriangles, RTCBuildQuality quality, RTCSceneFlags flags);
};

}  // namespace aperture
