#pragma once
// The one-view path shared by `aperture render` and `aperture batch`, so that a batch frame
// equals a render with the same camera, bit for bit.
#include <string>
#include <vector>

#include "cameras/params.h"
#include "core/exr.h"
#include "core/framebuffer.h"
#include "core/image.h"
#include "core/mesh.h"
#include "core/render.h"
#include "core/scene.h"

namespace aperture::app {

/// A rendered view with what its file header records.
struct RenderedView {
  Framebuffer fb;
  RenderStats stats;
  CameraDescription camera;
  NormalFrame normalFrame = NormalFrame::World;  ///< of normal and shading-normal
};

/// Builds the camera of `params` in the scene's render space and renders it into a fresh
/// framebuffer of the requested AOVs. Throws Error for a bad camera or settings.
RenderedView renderView(const Scene& scene, const CameraParams& params,
                        const RenderSettings& settings, const AovSet& aovs);

/// The header of a rendered view: camera, render time, meshes, AOVs, BVH quality and
/// traversal mode (robust or not), placement, and the normal frame when it holds normals.
ExrMetadata viewMetadata(const RenderedView& view, const std::vector<std::string>& meshNames,
                         const AovSet& aovs, const BuildOptions& build, Placement placement);

/// Creates the parent directory of `path`; throws Error("<what>: '<path>': cannot create
/// directory ...").
void ensureParentDirectory(const std::string& path, const std::string& what);

/// Where the camera sidecar of an EXR goes: its path with ".camera.json" for ".exr".
std::string cameraSidecarPath(const std::string& exrPath);

/// Writes the files of a rendered view in a fixed order: first the preview (when
/// `previewPath` is not empty, with `preview`), then (with `cameraSidecar`, for a camera that
/// has a calibrated form: calibratedViewOf) the camera sidecar JSON, then the EXR, each atomically
/// and each after creating its directory. A preview that cannot be written throws before the EXR is
/// started, so a complete EXR always has its preview beside it and `batch --resume`, which
/// looks at the EXR, renders a frame whose preview failed again. (A preview may remain when
/// the EXR then fails.) Throws Error naming the file that failed.
void writeViewOutputs(const RenderedView& view, const ExrMetadata& meta, const ExrOptions& exr,
                      const std::string& exrPath, const std::string& previewPath,
                      const PreviewOptions& preview = {}, bool cameraSidecar = false);

}  // namespace aperture::app
