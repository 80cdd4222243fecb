#pragma once
// --preset fast|balanced|exact: settings picked from the measured speed/accuracy frontier
// (bench/TRADEOFF.md has the numbers behind each). Explicit flags or job keys override them.
#include <string>
#include <vector>

#include "core/exr.h"
#include "core/render.h"
#include "core/scene.h"

namespace aperture::app {

struct Preset {
  std::string name;
  BuildOptions build;
  RenderSettings render;  ///< packet, tile, spp
  ExrOptions exr;
  std::string why;  ///< one line: the measurement that justifies it
};

/// The presets in order fast, balanced, exact.
const std::vector<Preset>& presets();
/// The preset called `name`; throws Error listing the known names.
const Preset& findPreset(const std::string& name);
/// "fast: ...; balanced: ...; exact: ..." for --help.
std::string presetHelp();

}  // namespace aperture::app
