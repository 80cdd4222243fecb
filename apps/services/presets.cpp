#include "apps/services/presets.h"

#include "core/util/error.h"

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

}  // namespace aperture::app
