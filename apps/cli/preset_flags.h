#pragma once
// The --preset flag of render and bench (the presets: apps/services/presets.h).
#include <CLI/CLI.hpp>
#include <string>

#include "apps/cli/camera_flags.h"
#include "apps/services/presets.h"
#include "apps/services/scene_setup.h"

namespace aperture::app {

void addPresetOption(CLI::App& app, std::string& preset);
/// Sets every knob of the preset that the command line did not give explicitly (`sub` is the
/// parsed subcommand); half/compression may be null where the command writes no EXR.
void applyPreset(const std::string& name, const CLI::App& sub, SceneOptions& scene,
                 CameraFlags& camera, bool* halfColor, std::string* compression);

}  // namespace aperture::app
