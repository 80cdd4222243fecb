#include "apps/view.h"

#include <filesystem>

#include "cameras/calibrated.h"
#include "cameras/camera_file.h"
#include "cameras/registry.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace aperture::app {

RenderedView renderView(const Scene& scene, const CameraParams& params,
                        const RenderSettings& settings, const AovSet& aovs) {
  const auto camera = makeCamera(params, scene.renderOrigin());
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

void writeViewOutputs(const RenderedView& view, const ExrMetadata& meta, const ExrOptions& exr,
                      const std::string& exrPath, const std::string& previewPath,
                      const PreviewOptions& preview, bool cameraSidecar) {
  if (!previewPath.empty()) {
    ensureParentDirectory(previewPath, "preview");
    writePreview(previewPath, view.fb, preview);
  }
  if (cameraSidecar)
    if (const std::optional<CalibratedView> cal = calibratedViewOf(view.camera)) {
      const std::string path = cameraSidecarPath(exrPath);
      ensureParentDirectory(path, "camera sidecar");
      writeTextAtomically(path, cameraSidecarJson(cal->sensor, cal->worldToCamera));
    }
  ensureParentDirectory(exrPath, "output");
  writeExr(exrPath, view.fb, meta, exr);
}

}  // namespace aperture::app
