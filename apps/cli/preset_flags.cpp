#include "apps/cli/preset_flags.h"

namespace aperture::app {

void addPresetOption(CLI::App& app, std::string& preset) {
  app.add_option(
      "--preset", preset,
      "fast (medium BVH, not robust, 1 spp, half color, no EXR compression), balanced (high robust "
      "BVH, 4 spp, zip) or exact (high robust BVH, 256 spp, float, zip); flags given "
      "explicitly win; measured in bench/TRADEOFF.md");
}

void applyPreset(const std::string& name, const CLI::App& sub, SceneOptions& scene,
                 CameraFlags& camera, bool* halfColor, std::string* compression) {
  if (name.empty()) return;
  const Preset& p = findPreset(name);
  if (sub.count("--bvh-quality") == 0) scene.quality = p.bvhQuality;
  if (sub.count("--robust") == 0) scene.robust = p.robust;  // counts --no-robust too
  if (sub.count("--spp") == 0) camera.defaults().spp = p.spp;
  if (halfColor && sub.count("--half") == 0) *halfColor = p.halfColor;
  if (compression && sub.count("--compression") == 0) *compression = p.compression;
}

}  // namespace aperture::app
