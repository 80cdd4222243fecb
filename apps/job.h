#pragma once
// Batch job files: a JSON description of one scene and many camera views (docs/batch.md).
#include <cstddef>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cameras/params.h"
#include "core/exr.h"
#include "core/framebuffer.h"
#include "core/image.h"
#include "core/render.h"
#include "core/scene.h"

namespace aperture::app {

/// One entry of scene.meshes.
struct JobMesh {
  std::string spec;  ///< file path (resolved against the job's directory) or "procedural:..."
  std::optional<glm::dmat4> worldFromMesh;  ///< placement; absent = identity
};

/// One image to render: a camera name, its frame number and everything the camera needs.
struct JobImage {
  size_t index = 0;     ///< position in job order over all cameras (what --shard selects on)
  std::string camera;   ///< the camera's name
  int frame = 0;        ///< frame number within the camera (0 for a fixed camera)
  CameraParams params;  ///< complete parameters (size and spp included)
  std::string output;   ///< EXR path, pattern expanded and resolved
  std::string preview;  ///< preview path, or "" when the job has no preview pattern
};

/// A parsed and fully validated job.
struct Job {
  std::string path;  ///< the job file
  std::vector<JobMesh> meshes;
  std::vector<JobImage> images;  ///< in job order: cameras as listed, path frames ascending
  AovMask aovs = 0;
  int width = 0, height = 0;
  RenderSettings render;  ///< packet, tile, spp
  int threads = 0;        ///< 0 = all cores
  BuildOptions build;
  bool cull = false;  ///< performance.cull: BVH over the triangles the frames may see
  Placement placement = Placement::CameraRelative;  ///< scene.placement
  ExrOptions exr;
  std::string outputPattern;   ///< as written in the job file
  std::string previewPattern;  ///< as written; "" for none
  /// "preview_range": the depth range of every preview; without it, `aperture batch` uses
  /// batchPreviewOptions (apps/outputs.h).
  PreviewOptions preview;
  /// The output pattern's directory up to the first placeholder, resolved (where summary.json
  /// goes by default); "." when the pattern starts with a placeholder.
  std::string outputDirectory;
};

/// Most frames one job may hold (so a malformed file cannot exhaust memory).
inline constexpr size_t kMaxJobImages = 100000;

/// Reads and validates a job file: unknown keys, types, ranges, mesh files (existence only,
/// nothing is loaded), output patterns (distinct outputs per frame) and every camera (each
/// frame's camera is constructed). Never crashes on malformed input: throws Error naming the
/// file, the JSON path of the value (e.g. "cameras[2].eyee") and the reason.
Job parseJob(const std::string& path);

/// parseJob on text already read; `name` is used in messages and relative paths resolve
/// against `baseDir`.
Job parseJobText(const std::string& text, const std::string& name, const std::string& baseDir);

/// Expands {camera}, {frame} and {frame:0Nd} (N in 1..20) in `pattern`. Throws Error for
/// any other brace.
std::string expandOutputPattern(const std::string& pattern, const std::string& camera, int frame);

/// A turntable path: see docs/batch.md for the formula.
struct OrbitPath {
  glm::dvec3 centre{0.0};
  double radius = 1;                   ///< scene units (> 0)
  std::optional<double> height;        ///< offset along up, scene units
  std::optional<double> elevationDeg;  ///< angle above the orbit plane, degrees
  double startDeg = 0;                 ///< azimuth of frame 0, degrees
  double sweepDeg = 360;               ///< azimuth covered by `frames` frames, degrees
  int frames = 1;
  glm::dvec3 up{0.0, 1.0, 0.0};
};

/// Eye position of frame k of an orbit.
glm::dvec3 orbitEye(const OrbitPath& orbit, int k);

/// One keyframe of a keyframed path.
struct Keyframe {
  int frame = 0;
  glm::dvec3 eye{0.0}, at{0.0}, up{0.0, 1.0, 0.0};
  std::optional<double> fovDeg;
};

/// The keyframe values at frame f: linear interpolation between the keyframes around f,
/// held constant before the first and after the last. Keyframes ascend strictly by frame.
Keyframe interpolateKeyframes(const std::vector<Keyframe>& keys, int f);

}  // namespace aperture::app
