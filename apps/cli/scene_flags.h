#pragma once
// The scene flags of render, bench, tradeoff and visibility: meshes, BVH, culling, memory.
#include <CLI/CLI.hpp>

#include "apps/services/scene_setup.h"

namespace aperture::app {

void addSceneOptions(CLI::App& app, SceneOptions& o);

}  // namespace aperture::app
