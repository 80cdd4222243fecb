#pragma once
// --preset fast|balanced|exact: settings picked from the measured speed/accuracy frontier
// (bench/TRADEOFF.md), for render, bench and job files; the flag: apps/cli/preset_flags.h.
#include <string>

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

}  // namespace aperture::app
