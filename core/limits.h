#pragma once
// Memory estimates made before anything is loaded, and the --max-memory check.
#include <cstdint>
#include <string>
#include <vector>

#include "core/framebuffer.h"

namespace aperture {

/// What a mesh will hold once loaded, from a cheap look at the file (never a full parse).
struct MeshSizeEstimate {
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  uint64_t fileBytes = 0;
  uint64_t loaderBytes = 0;  ///< peak bytes of the loader's buffers (positions, indices)
  std::string how;           ///< "PLY header", "OBJ sample of N bytes", "procedural spec"
};

/// Estimates `spec` (a .ply or .obj path or a procedural spec): a PLY's counts from its header
/// as the loader reads it (readPlyHeader; at most 1 MiB read; binary polygons and strips from
/// the bytes their lists take, strips as an upper bound), an OBJ's from 1 MiB sampled across
/// the file and scaled, a procedural mesh's from the generator (proceduralMeshCounts). Counts a
/// file could not hold are clamped to its size. Never throws: an unreadable path, a header the
/// loader rejects or a bad procedural spec is left to the loader, which names the problem.
MeshSizeEstimate estimateMeshSize(const std::string& spec);

/// Bytes per pixel of the requested AOVs' framebuffers.
uint64_t framebufferBytesPerPixel(const AovSet& aovs);

/// Bytes of Embree BVH per triangle assumed by the estimate (a high-quality build with
/// triangle4 leaves measures 70-80 bytes; low and medium builds use less).
inline constexpr uint64_t kBvhBytesPerTriangle = 80;

/// Resident bytes of the process before any job: code of the libraries (Embree, TBB, OpenEXR,
/// OpenImageIO), thread stacks and arenas; measured at about 135 MB.
inline constexpr uint64_t kRuntimeBytes = 128ull << 20;

/// A job's memory, by part.
struct MemoryEstimate {
  uint64_t meshBytes = 0;         ///< loader buffers of every mesh, and the mapped files
  uint64_t bvhBytes = 0;          ///< kBvhBytesPerTriangle per triangle
  uint64_t framebufferBytes = 0;  ///< AOV buffers plus per-pixel extras (preview, half copy)
  uint64_t runtimeBytes = 0;      ///< kRuntimeBytes
  uint64_t triangles = 0;
  uint64_t total() const { return meshBytes + bvhBytes + framebufferBytes + runtimeBytes; }
  /// "1.2 GB (meshes 400 MB for 5000000 triangles, BVH 400 MB, framebuffers 400 MB)".
  std::string describe() const;
};

/// Estimates the memory of rendering `meshSpecs` at width x height with `aovs`;
/// `extraBytesPerPixel` covers outputs made beside the framebuffer (a PNG preview: 4).
MemoryEstimate estimateMemory(const std::vector<std::string>& meshSpecs, uint64_t width,
                              uint64_t height, const AovSet& aovs, uint64_t extraBytesPerPixel = 0);

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
