#pragma once
// Memory estimates made before anything is loaded, and the --max-memory check.
#include <cstdint>
#include <string>
#include <vector>

#include "core/aov/framebuffer.h"
#include "core/engine/scene.h"

namespace aperture {

/// What a mesh will hold once loaded, from a cheap look at the file (never a full parse).
struct MeshSizeEstimate {
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  uint64_t fileBytes = 0;
  /// Peak bytes while the loader runs: its buffers and temporaries (double positions, the
  /// finite-vertex flags, vectors grown by push_back) and the mapped file's pages.
  uint64_t loaderBytes = 0;
  /// Bytes kept once loaded, shared with Embree: float positions (padded) and indices.
  uint64_t meshBytes = 0;
  std::string how;  ///< "PLY header", "OBJ sample of N bytes", "glTF JSON", "procedural spec"
  /// True where the triangle order is known to keep neighbours together, so a large mesh is
  /// built in chunks as it is (kMaxChunksPerCell): the procedural generators make their shapes
  /// one after the other. A file's order is known only once it is loaded: a large one is
  /// estimated as put in spatial order first (orderTrianglesInSpace, core/engine/triangle_order.h),
  /// which keeps 4 more bytes per triangle (its loaded indices), then built in chunks.
  bool spatiallyOrdered = false;
};

/// Estimates `spec` (a .ply, .obj, .gltf or .glb path or a procedural spec): a PLY's counts
/// from its header as the loader reads it (readPlyHeader; at most 1 MiB read; binary polygons
/// and strips from the bytes their lists take, strips as an upper bound), an OBJ's from 1 MiB
/// sampled across the file and scaled, a glTF file's from its JSON alone (a .glb's JSON chunk;
/// every mesh counted once, by the counts its accessors declare, whether its scene places it
/// or not, so an upper bound for one scene; no buffer is read or decoded), a procedural mesh's
/// from the generator (proceduralMeshCounts). Counts a
/// file could not hold are clamped to its size. Never throws: an unreadable path, a header the
/// loader rejects or a bad procedural spec is left to the loader, which names the problem.
MeshSizeEstimate estimateMeshSize(const std::string& spec);

/// Bytes per pixel of the requested AOVs' framebuffers.
uint64_t framebufferBytesPerPixel(const AovSet& aovs);

// The memory model (calibrated with `aperture bench --scaling` on procedural:spheres from 1e5
// to 1e7 triangles, Embree 3.13.5, robust high-quality BVH; each figure is a child process's
// VmHWM). A job's resident memory goes through three phases, one after the other, and its
// peak is the largest of them on top of the runtime:
//   loading    the loaders' peak (MeshSizeEstimate::loaderBytes; meshes load one at a time,
//              the ones loaded before are kept);
//   building   the kept mesh buffers (Embree reads them: they are shared, not copied) plus
//              Embree's build peak: the finished BVH and, until the build ends, its array of
//              32-byte primitive references, one per triangle of the BVH being built: a
//              mesh built in chunks (BuildOptions::bvhChunkTriangles; a file first put in
//              spatial order, see MeshSizeEstimate::spatiallyOrdered; the sort's 18 bytes per
//              triangle are freed before the build) holds one chunk's at a time, the other
//              meshes are built together in the top-level BVH;
//   rendering  the mesh buffers, the BVH and the framebuffers (allocated after the build, in
//              the pages the primitive references gave back).
// The direction tables of distorted calibrated cameras (MemoryEstimate::lensTableBytes) are
// made with the cameras, which a job file makes when it is read, and counted beside every
// phase.
// Measured at 1e7 triangles: mesh 18.0 B/tri (12 B per vertex, 12 per triangle, 0.5 vertices
// per triangle), build peak 97.5 B/tri above the mesh (BVH 65.2 + references 32.3), BVH after
// the build 65-69 B/tri. The compact BVH (RTC_SCENE_FLAG_COMPACT: triangles kept as indices
// into the shared buffers): build peak 39.3 B/tri above the mesh, BVH 36 B/tri resident.
// Low and medium quality and non-robust builds were not calibrated: the robust high figures
// are used for them (a non-robust high build measured 7% above them at 1e7).

/// Embree's resident bytes per triangle after a (robust, high-quality) build.
inline constexpr uint64_t kBvhBytesPerTriangle = 66;
/// Embree's peak bytes per triangle during that build: the BVH and the primitive references.
inline constexpr uint64_t kBvhBuildBytesPerTriangle = 98;
/// The same with the compact BVH.
inline constexpr uint64_t kCompactBvhBytesPerTriangle = 36;
inline constexpr uint64_t kCompactBvhBuildBytesPerTriangle = 40;

/// Resident bytes of the process before any job: the shared libraries' pages (Embree, TBB,
/// OpenEXR), thread stacks and arenas; `aperture --version` peaks at 9.5 MB, and bench
/// --scaling at 1e5 triangles leaves about 7 MB beside its mesh, BVH and framebuffers. It also
/// covers the coverage mask's occupancy grid (core/engine/occupancy.h: 7 MB of cell marks while it
/// is built, after the BVH's build peak, then 8 bytes per run of occupied cells).
inline constexpr uint64_t kRuntimeBytes = 10ull << 20;
/// What the image codec (core/io/image_codec.h: OpenImageIO and the libraries it brings) adds
/// once loaded, for a job that writes or reads PNG, JPEG or TIFF files: 122 MB measured, a
/// 320x240 render with a PNG preview against the same render without.
inline constexpr uint64_t kImageCodecBytes = 124ull << 20;

/// A job's memory, by part (see the model above).
struct MemoryEstimate {
  uint64_t loadPeakBytes = 0;     ///< the largest loading peak (meshes loaded before included)
  uint64_t meshBytes = 0;         ///< mesh buffers kept for Embree, every mesh
  uint64_t bvhBuildBytes = 0;     ///< Embree's peak during the build
  uint64_t bvhBytes = 0;          ///< Embree's BVH after the build
  uint64_t framebufferBytes = 0;  ///< AOV buffers plus per-pixel extras (preview, half copy)
  uint64_t runtimeBytes = 0;      ///< kRuntimeBytes
  uint64_t imageCodecBytes = 0;   ///< kImageCodecBytes when the job uses the image codec
  /// Direction tables of distorted calibrated cameras (cameras/lenses/direction_table.h), made with
  /// the cameras and kept in a cache: counted in every phase (a job file's cameras are made
  /// when it is read, before anything loads).
  uint64_t lensTableBytes = 0;
  uint64_t triangles = 0;
  uint64_t buildPhaseBytes() const { return meshBytes + bvhBuildBytes; }
  uint64_t renderPhaseBytes() const { return meshBytes + bvhBytes + framebufferBytes; }
  /// The runtime, the image codec and the lens tables, plus the largest of the three phases.
  uint64_t total() const;
  /// "1.2 GB (meshes 400 MB for 5000000 triangles, BVH 400 MB, framebuffers 400 MB)".
  std::string describe() const;
};

/// Estimates the memory of rendering `meshSpecs` (each mesh placed once) at width x height
/// with `aovs`; `extraBytesPerPixel` covers outputs made beside the framebuffer (a PNG
/// preview: 4); `build` for the compact BVH (--compact) and the chunked build of large meshes
/// (BuildOptions::bvhChunkTriangles).
MemoryEstimate estimateMemory(const std::vector<std::string>& meshSpecs, uint64_t width,
                              uint64_t height, const AovSet& aovs, uint64_t extraBytesPerPixel = 0,
                              const BuildOptions& build = {});

/// MemAvailable from /proc/meminfo, in bytes. Throws Error if it cannot be read.
uint64_t availableMemoryBytes();

/// Parses a --max-memory value: "auto" (MemAvailable), or a positive byte count with an
/// optional suffix K, M, G, T (powers of 1024; "KiB", "MB" and the like also accepted).
/// "" means no limit and returns 0. Throws Error naming `flag` for anything else.
uint64_t parseMemoryLimit(const std::string& flag, const std::string& text);

/// Throws Error("... needs about X, more than the limit of Y (flag)") when estimate > limit;
/// limit 0 means none.
void checkMemoryLimit(const MemoryEstimate& estimate, uint64_t limit, const std::string& flag,
                      const std::string& limitText);

/// "1.5 GB", "320 MB", "12 KB" (decimal units) for messages.
std::string formatBytes(uint64_t bytes);

}  // namespace aperture
