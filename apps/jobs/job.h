#pragma once
// Batch job files: a JSON description of one scene and many camera views, or of several such
// scenes sharing their settings ("scenes", docs/batch.md).
#include <algorithm>
#include <cstddef>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "apps/jobs/camera_paths.h"
#include "apps/jobs/job_camera.h"
#include "apps/jobs/job_lidar.h"
#include "apps/services/scene_setup.h"
#include "apps/services/view.h"
#include "cameras/schema/params.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/exr/exr.h"
#include "core/io/dataset_image.h"
#include "core/io/image.h"

namespace aperture::app {

/// One image to render: a camera name, its frame number and everything the camera needs.
struct JobImage {
  /// Position in job order over all cameras, and over all scenes in a job with "scenes"
  /// (what --shard selects on and --resume reports).
  size_t index = 0;
  size_t scene = 0;     ///< its scene's position in JobFile::scenes (0 without "scenes")
  std::string camera;   ///< the camera's name
  int frame = 0;        ///< frame number within the camera (0 for a fixed camera)
  CameraParams params;  ///< complete parameters (size and spp included)
  /// The image's main file, pattern expanded and resolved: its EXR, or, for a job that writes
  /// no EXR (Job::writesExr), its first "outputs" file. What logs and resume messages name.
  std::string output;
  std::string preview;                  ///< preview path, or "" when the job has no preview pattern
  std::vector<DatasetOutput> datasets;  ///< the "outputs" entries that are not EXR, expanded
  /// Every file the image writes, in the order writeViewOutputs writes them (viewFilePaths).
  std::vector<std::string> files;
};

/// A non-EXR entry of the job's "outputs": one AOV of every image in a dataset format.
struct JobDatasetOutput {
  std::string aov;        ///< one AOV, among the job's "aovs"
  std::string pattern;    ///< as written, with placeholders
  std::string directory;  ///< the pattern's directory up to the first placeholder, resolved
};

/// A parsed and fully validated job.
struct Job {
  std::string path;                   ///< the job file
  std::string sceneName;              ///< the entry's "name" in a job with "scenes", else ""
  std::vector<MeshPlacement> meshes;  ///< scene.meshes, paths resolved against the job
  std::vector<JobImage> images;       ///< in job order: cameras as listed, path frames ascending
  AovSet aovs;
  int width = 0, height = 0;
  RenderSettings render;  ///< packet, tile, spp
  int threads = 0;        ///< 0 = all cores
  BuildOptions build;
  bool cull = false;  ///< performance.cull: BVH over the triangles the frames may see
  Placement placement = Placement::CameraRelative;  ///< scene.placement
  /// scene.gltf_scene: the scene of every glTF mesh file (SceneSpec::gltfScene); unset: each
  /// file's default scene.
  std::optional<int> gltfScene;
  /// The scene to load and build: meshes, placement, BVH options, culling, the glTF scene, the
  /// mesh data the AOVs read and what the LiDAR scans need (withScanNeeds).
  SceneSpec sceneSpec() const {
    SceneSpec spec;
    spec.meshes = meshes;
    spec.placement = placement;
    spec.build = build;
    spec.cull = cull;
    spec.gltfScene = gltfScene;
    spec = withAovNeeds(spec, aovs);
    for (const JobLidar& l : lidars) spec = withScanNeeds(spec, l.request.options);
    return spec;
  }
  /// "lidars": LiDAR sensors scanned through the job's scene after its images (job_lidar.h).
  std::vector<JobLidar> lidars;
  /// "id_counts": summary.json reports per image the pixel count of each id of the property
  /// AOVs and geomid (batchIdCounts).
  bool idCounts = false;
  ExrOptions exr;
  /// "camera_files": beside each EXR a camera sidecar (<name>.camera.json) and, after the
  /// run, a COLMAP text model of every image rendered (<output directory>/sparse). Default:
  /// on for cameras from a camera file, off otherwise.
  bool cameraFiles = false;
  /// The job writes an EXR of every AOV per image ("output", or an "outputs" entry ending in
  /// .exr); false when "outputs" names dataset files only.
  bool writesExr = true;
  std::string outputPattern;               ///< the EXR pattern as written ("" when !writesExr)
  std::vector<JobDatasetOutput> datasets;  ///< "outputs" entries other than the EXR, in order
  DatasetWriteOptions dataset;             ///< "depth_scale"
  std::string previewPattern;              ///< as written; "" for none
  /// "preview_range": the depth range of every preview; without it, `aperture batch` uses
  /// batchPreviewOptions (apps/jobs/job_outputs.h).
  PreviewOptions preview;
  /// The output pattern's directory up to the first placeholder, resolved (where summary.json
  /// goes by default); "." when the pattern starts with a placeholder.
  std::string outputDirectory;
};

/// Reads and validates a job file: unknown keys, types, ranges, mesh files (existence only,
/// nothing is loaded), output patterns (distinct outputs per frame) and every camera (each
/// frame's camera is constructed). Never crashes on malformed input: throws Error naming the
/// file, the JSON path of the value (e.g. "cameras[2].eyee") and the reason.
Job parseJob(const std::string& path);

/// parseJob on text already read; `name` is used in messages and relative paths resolve
/// against `baseDir`. Both refuse a job with "scenes" (readJobFile reads it).
Job parseJobText(const std::string& text, const std::string& name, const std::string& baseDir);

/// A job file as read: one Job per scene. A file with "scenes" lists several scenes (a
/// dataset of scans): each entry, merged over the file's other top-level keys (the entry's
/// own keys win), is read as a one-scene job, so every check applies; {scene} in the output
/// patterns is the entry's "name" (required with more than one scene). A file without
/// "scenes" is one scene. Image indices run over all scenes in order.
struct JobFile {
  std::string path;
  std::vector<Job> scenes;
  bool multiScene = false;  ///< the file has "scenes"
  /// Where summary.json goes by default: the first scene's output pattern's directory up to
  /// its first placeholder ({scene} included).
  std::string outputDirectory;
  size_t imageCount() const;
};

/// Reads a job file of one scene or of "scenes" (messages name the JSON path, e.g.
/// "scenes[3].cameras[0].eye").
JobFile readJobFile(const std::string& path);
/// readJobFile on text already read (`name` in messages, paths relative to `baseDir`).
JobFile readJobFileText(const std::string& text, const std::string& name,
                        const std::string& baseDir);

/// The one-line form `aperture batch --mesh MESH --cameras PATH --out DIR --aov LIST`: every
/// image of a camera file (or those --image names) to DIR/<image name>.exr, subfolders kept.
struct CameraFileBatch {
  std::vector<std::string> meshes;
  std::optional<int> gltfScene;  ///< --gltf-scene: the job's scene.gltf_scene
  std::string cameras;
  std::vector<std::string> images;
  std::string outDir;
  std::string aovs = "depth";
  std::optional<int> spp;
  /// --size W,H: the image size of cameras that carry none (glTF cameras; the job's "size").
  std::optional<std::vector<int>> size;
  bool preview = false;  ///< also DIR/<image name>.png
  /// --format: exr (every AOV in DIR/<image name>.exr) or a dataset format (png pfm npy tif
  /// tiff: the one AOV of --aov in DIR/<image name>.<format>).
  std::string format = "exr";
  std::optional<double> depthScale;   ///< --depth-scale
  std::string normalFrame = "world";  ///< --normal-frame: the job's "normal_frame"
  bool idCounts = false;              ///< --id-counts: the job's "id_counts"
  std::optional<int> layers;          ///< --layers K
  bool deep = false;                  ///< --deep: the job's "deep"
};
/// The job of a CameraFileBatch: written as a job file's JSON and read by parseJobText, so the
/// one-line form and job files share every check.
Job cameraFileJob(const CameraFileBatch& b);

/// Expands {camera}, {frame}, {frame:0Nd} (N in 1..20) and, for an image of a camera file,
/// {image} (its name without the extension, subfolders kept) in `pattern`. Throws Error for
/// any other brace ({scene} is replaced before, by readJobFile).
std::string expandOutputPattern(const std::string& pattern, const std::string& camera, int frame,
                                const std::string& image = "");

}  // namespace aperture::app
