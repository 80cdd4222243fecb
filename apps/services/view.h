#pragma once
// The one-view path shared by `aperture render` and `aperture batch`, so that a batch frame
// equals a render with the same camera, bit for bit.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cameras/schema/params.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/exr/exr.h"
#include "core/io/dataset_image.h"
#include "core/io/image.h"
#include "core/mesh/mesh.h"

namespace aperture::app {

/// A rendered view with what its file header records.
struct RenderedView {
  Framebuffer fb;
  RenderStats stats;
  CameraDescription camera;
  NormalFrame normalFrame = NormalFrame::World;  ///< of normal and shading-normal
};

/// What turns the camera of `params` into the one rendered (a rolling shutter,
/// cameras/lidar/rolling_shutter.h), given it and the scene's render origin; empty: the camera
/// itself.
using CameraWrap = std::function<std::shared_ptr<const Camera>(std::shared_ptr<const Camera>,
                                                               const glm::dvec3& renderOrigin)>;

/// Builds the camera of `params` in the scene's render space (through `wrap` when given) and
/// renders it into a fresh framebuffer of the requested AOVs. Throws Error for a bad camera or
/// settings.
RenderedView renderView(const Scene& scene, const CameraParams& params,
                        const RenderSettings& settings, const AovSet& aovs,
                        const CameraWrap& wrap = {});

/// The header of a rendered view: camera, render time, meshes, AOVs, BVH quality and
/// traversal mode (robust or not), placement, and the normal frame when it holds normals.
ExrMetadata viewMetadata(const RenderedView& view, const std::vector<std::string>& meshNames,
                         const AovSet& aovs, const BuildOptions& build, Placement placement);

/// Creates the parent directory of `path`; throws Error("<what>: '<path>': cannot create
/// directory ...").
void ensureParentDirectory(const std::string& path, const std::string& what);

/// Where the camera sidecar of an EXR goes: its path with ".camera.json" for ".exr".
std::string cameraSidecarPath(const std::string& exrPath);

/// One AOV of a view written alone in a dataset format (core/io/dataset_image.h): `aov` as
/// aovView spells it, `path` ending in one of datasetExtensions().
struct DatasetOutput {
  std::string aov;
  std::string path;
  DatasetFormat format() const;  ///< by the extension of `path`
  bool operator==(const DatasetOutput& o) const { return aov == o.aov && path == o.path; }
};

/// The files of a view in the order writeViewOutputs writes them (the camera sidecar, which
/// only some cameras have, aside): the preview, the dataset files in order, with
/// `deepLayers` (ExrOptions::layersInDeepFile) the deep file of the EXR (deepLayersPath), the
/// EXR. Empty paths are left out.
std::vector<std::string> viewFilePaths(const std::string& exrPath, const std::string& previewPath,
                                       const std::vector<DatasetOutput>& datasets,
                                       bool deepLayers = false);

/// Writes the files of a rendered view in a fixed order: first the preview (when
/// `previewPath` is not empty, with `preview`), then the dataset files (`datasets`, with
/// `dataset`), then (with `cameraSidecar`, for a camera that has a calibrated form:
/// calibratedViewOf) the camera sidecar JSON beside the EXR (beside the first dataset file
/// when there is no EXR), then, with `exr.layersInDeepFile` and layers in the view, the deep
/// file of the layers (core/exr/exr_deep.h, deepLayersPath(exrPath)), then the EXR (when `exrPath`
/// is not empty; without the hit<k>.* channels when they went to the deep file), each
/// atomically and each
/// after creating its directory. A file that cannot be written throws before the EXR is
/// started, so a complete EXR always has its other files beside it and `batch --resume`,
/// which looks at the EXR first, renders a frame whose preview failed again. (Earlier files
/// may remain when a later one fails.) A 16-bit PNG with values out of range prints a warning
/// naming the file and the count on stderr. Throws Error naming the file that failed.
void writeViewOutputs(const RenderedView& view, const ExrMetadata& meta, const ExrOptions& exr,
                      const std::string& exrPath, const std::string& previewPath,
                      const PreviewOptions& preview = {}, bool cameraSidecar = false,
                      const std::vector<DatasetOutput>& datasets = {},
                      const DatasetWriteOptions& dataset = {});

}  // namespace aperture::app
