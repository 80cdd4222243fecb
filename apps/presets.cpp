#include "apps/presets.h"

#include "core/error.h"

namespace aperture::app {

namespace {
// Justified in bench/TRADEOFF.md (bunny, crown with its thin lens, bathroom):
//  fast: a medium BVH builds 3-35x faster than high and traces within 2 %; half color and no
//        EXR compression cut the write from 22-57 ms to 6-13 ms a frame (geometry stays float);
//        it is the one place robust traversal (the default since issue 15) is turned off.
//  balanced: high + robust removes every primID mismatch at <= 8 % trace cost; 4 spp buys
//        5.5-6.4 dB of color PSNR for 3.4-5x the frame time.
//  exact: the study's reference itself: high, robust, 256 spp, float color, lossless zip.
const Preset kPresets[] = {
    {"fast", "medium", false, 1, true, "none"},
    {"balanced", "high", true, 4, false, "zip"},
    {"exact", "high", true, 256, false, "zip"},
};
}  // namespace

const Preset& findPreset(const std::string& name) {
  for (const Preset& p : kPresets)
    if (name == p.name) return p;
  throw Error(cat("--preset: unknown preset '", name, "' (known: fast, balanced, exact)"));
}

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
