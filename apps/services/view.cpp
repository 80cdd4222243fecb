#include "apps/services/view.h"

#include <cstdio>
#include <filesystem>

#include "cameras/files/camera_file.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/exr/exr_deep.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"

namespace aperture::app {

RenderedView renderView(const Scene& scene, const CameraParams& params,
                        const RenderSettings& settings, const AovSet& aovs,
                        const CameraWrap& wrap) {
  std::shared_ptr<const Camera> camera = makeCamera(params, scene.renderOrigin());
  if (wrap) camera = wrap(std::move(camera), scene.renderOrigin());
  RenderedView view;
  view.fb = Framebuffer(params.width, params.height, aovs);
  RenderSettings forCamera = settings;
  forCamera.spp = params.spp;  // a job camera may set its own spp
  view.stats = renderImage(scene, *camera, forCamera, view.fb);
  view.camera = camera->describe();
  view.normalFrame = settings.normalFrame;
  return view;
}

ExrMetadata viewMetadata(const RenderedView& view, const std::vector<std::string>& meshNames,
                         const AovSet& aovs, const BuildOptions& build, Placement placement) {
  ExrMetadata meta;
  meta.camera = view.camera;
  meta.renderSeconds = view.stats.seconds;
  const std::string meshes = join(meshNames, ";");
  meta.strings = {{"aperture.meshes", meshes},
                  {"aperture.aovs", aovListString(aovs)},
                  {"aperture.bvhQuality", bvhQualityName(build.quality)},
                  {"aperture.robust", build.robust ? "true" : "false"},
                  {"aperture.placement",
                   placement == Placement::WorldSpace ? "world-space" : "camera-relative"}};
  if (view.fb.has(kAovNormal) || view.fb.has(kAovShadingNormal))
    meta.strings.emplace_back("aperture.normalFrame", normalFrameName(view.normalFrame));
  return meta;
}

void ensureParentDirectory(const std::string& path, const std::string& what) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(parent, ec);
  if (ec)
    throw Error(cat(what, ": '", path, "': cannot create directory '", parent.string(),
                    "': ", ec.message()));
}

std::string cameraSidecarPath(const std::string& exrPath) {
  return std::filesystem::path(exrPath).replace_extension(".camera.json").string();
}

DatasetFormat DatasetOutput::format() const {
  const std::optional<DatasetFormat> f = datasetFormatOf(path);
  if (!f)
    throw Error(cat("'", path, "': not a dataset file name (extensions: ",
                    join(datasetExtensions(), " "), ")"));
  return *f;
}

std::vector<std::string> viewFilePaths(const std::string& exrPath, const std::string& previewPath,
                                       const std::vector<DatasetOutput>& datasets,
                                       bool deepLayers) {
  std::vector<std::string> paths;
  if (!previewPath.empty()) paths.push_back(previewPath);
  for (const DatasetOutput& d : datasets) paths.push_back(d.path);
  if (exrPath.empty()) return paths;
  if (deepLayers) paths.push_back(deepLayersPath(exrPath));
  paths.push_back(exrPath);
  return paths;
}

namespace {

void writeDatasetOutput(const RenderedView& view, const DatasetOutput& d,
                        const DatasetWriteOptions& options) {
  ensureParentDirectory(d.path, "output");
  const DatasetWriteStats stats =
      writeDatasetImage(d.path, d.format(), aovView(view.fb, d.aov), d.aov, options);
  if (stats.outOfRange > 0)
    std::fprintf(stderr,
                 "aperture: warning: %s: %zu %s values outside [1, 65535] after scaling by %g "
                 "written as 0 (invalid)\n",
                 d.path.c_str(), stats.outOfRange, d.aov.c_str(), options.depthScale);
}

}  // namespace

void writeViewOutputs(const RenderedView& view, const ExrMetadata& meta, const ExrOptions& exr,
                      const std::string& exrPath, const std::string& previewPath,
                      const PreviewOptions& preview, bool cameraSidecar,
                      const std::vector<DatasetOutput>& datasets,
                      const DatasetWriteOptions& dataset) {
  if (!previewPath.empty()) {
    ensureParentDirectory(previewPath, "preview");
    writePreview(previewPath, view.fb, preview);
  }
  for (const DatasetOutput& d : datasets) writeDatasetOutput(view, d, dataset);
  const std::string sidecarBeside = !exrPath.empty()   ? exrPath
                                    : datasets.empty() ? std::string()
                                                       : datasets.front().path;
  if (cameraSidecar && !sidecarBeside.empty())
    if (const std::optional<CalibratedView> cal = calibratedViewOf(view.camera)) {
      const std::string path = cameraSidecarPath(sidecarBeside);
      ensureParentDirectory(path, "camera sidecar");
      writeTextAtomically(path, cameraSidecarJson(cal->sensor, cal->cvCameraFromWorld));
    }
  if (exrPath.empty()) return;
  ensureParentDirectory(exrPath, "output");
  if (exr.layersInDeepFile && view.fb.layers > 0)
    writeDeepLayersExr(deepLayersPath(exrPath), view.fb, meta);
  writeExr(exrPath, view.fb, meta, exr);
}

}  // namespace aperture::app
