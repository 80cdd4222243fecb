#pragma once
// --preset fast|balanced|exact: settings picked from the measured speed/accuracy frontier
// (bench/TRADEOFF.md), for render, bench and job files.
#include <CLI/CLI.hpp>
#include <string>

#include "apps/camera_flags.h"
#include "apps/scene_setup.h"

namespace aperture::app {

/// A --preset: settings picked from the measured speed/accuracy frontier (bench/TRADEOFF.md).
struct Preset {
  const char* name;
  const char* bvhQuality;
  bool robust;
  int spp;
  bool halfColor;
  const char* compression;
};
/// fast, balanced or exact; throws Error listing the names for anything else.
const Preset& findPreset(const std::string& name);
void addPresetOption(CLI::App& app, std::string& preset);
/// Sets every knob of the preset that the command line did not give explicitly (`sub` is the
/// parsed subcommand); half/compression may be null where the command writes no EXR.
void applyPreset(const std::string& name, const CLI::App& sub, SceneOptions& scene,
                 CameraFlags& camera, bool* halfColor, std::string* compression);

}  // namespace aperture::app
