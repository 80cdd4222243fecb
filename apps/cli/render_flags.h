#pragma once
// The frame-loop flags (AOVs, packet width, tile size, threads, layers, deep).
#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "apps/services/render_options.h"

namespace aperture::app {

void addRenderOptions(CLI::App& app, RenderOptions& o);
/// The --layers flag alone (render and bench add it through addRenderOptions).
void addLayersOption(CLI::App& app, std::optional<int>& layers, const std::string& group = "");
/// --layers help: what it records and where (docs/layers.md).
extern const char* const kLayersHelp;
/// The --deep flag of render and the one-line batch: the layers to <out stem>.deep.exr.
void addDeepOption(CLI::App& app, bool& deep, const std::string& group = "");

}  // namespace aperture::app
