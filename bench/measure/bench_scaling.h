#pragma once
// `aperture bench --scaling`: the procedural spheres scene from 1e5 to 1e8 triangles, each size
// measured in a fresh child `aperture bench` of the same executable, and the memory figures
// every bench run reports (peak resident memory, mesh buffers, the --max-memory estimate).
//
// Why a child per size: the peak resident set (VmHWM, as getrusage's ru_maxrss) only grows
// over a process's life, and allocators keep freed pages, so sizes measured one after another
// in one process would each see the peaks of the ones before. A fresh process per size gives
// each its own peak; the child reads its own VmHWM (a parent's wait4 ru_maxrss would start
// from the parent's resident set copied at fork).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/services/limits.h"

namespace aperture::app {

struct LoadedScene;
struct SceneOptions;

/// The sizes `--scaling` measures when `--scaling-sizes` is not given.
inline constexpr const char* kDefaultScalingSizes = "1e5,1e6,1e7,4e7,1e8";

/// Triangle counts of a --scaling-sizes list ("1e5,2.5e6,300000"): whole numbers in
/// [100, 4e8] (the spheres generator's range), comma-separated. Throws Error naming
/// --scaling-sizes and the bad value.
std::vector<uint64_t> parseScalingSizes(const std::string& text);

/// The scene measured at `triangles`: "procedural:spheres?tris=N" (within 1% of N).
std::string scalingMeshSpec(uint64_t triangles);

/// The arguments of the child bench measuring one size: the parent's own arguments `parent`
/// (argv[1..], as in /proc/self/cmdline) without the scaling run's flags (--scaling,
/// --scaling-sizes, --json, --mesh, --compact, --baseline, --builds, --quiet, in either the
/// "--flag value" or the "--flag=value" form), then the size's mesh, --baseline, one build,
/// --quiet, --json `rowJson`, and --compact when `compact`.
std::vector<std::string> scalingChildArguments(const std::vector<std::string>& parent,
                                               uint64_t triangles, bool compact,
                                               const std::string& rowJson);

/// This process's peak resident set since it started (VmHWM of /proc/self/status), bytes.
uint64_t peakResidentBytes();

/// Peak resident memory of one bench run at its stages, bytes (VmHWM read after each).
struct MemoryPeaks {
  uint64_t afterBuild = 0;      ///< meshes loaded, BVH built
  uint64_t beforeBaseline = 0;  ///< the frame loop's frames rendered (what `render` needs)
  uint64_t atEnd = 0;           ///< with the baseline's stored packets and any sweep
};

/// The "memory" object of a bench JSON: the peaks, the mesh buffers, Embree's memory, and the
/// --max-memory estimate beside the peak before the baseline (the estimate models a render:
/// load, build and frames; the baseline's stored rays are the bench's own), with its error
/// in % of the peak.
nlohmann::json benchMemoryReport(const LoadedScene& loaded, const MemoryEstimate& estimate,
                                 const MemoryPeaks& peaks);

/// The --max-memory estimate of the scene of `o` (its BVH flags included) rendered at
/// width x height with `aovs`.
MemoryEstimate benchMemoryEstimate(const SceneOptions& o, int width, int height,
                                   const AovSet& aovs);

/// What `--scaling` was asked for.
struct ScalingRun {
  std::vector<uint64_t> sizes;
  bool compact = false;  ///< also every size with a compact BVH: a second row set
  std::string json;      ///< "" or where the rows go; the Markdown table goes beside it (.md)
};

/// Measures every size in a child bench of this executable (its own arguments passed on, see
/// scalingChildArguments), prints the Markdown table on stdout (the children's output goes
/// to stderr) and writes the JSON and the table. Throws Error naming the size whose child
/// failed.
int runScaling(const ScalingRun& run);

}  // namespace aperture::app
