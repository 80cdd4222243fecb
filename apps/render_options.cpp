#include "apps/render_options.h"

#include <tbb/global_control.h>

#include "core/aov_table.h"
#include "core/error.h"
#include "core/layers.h"

namespace aperture::app {

const char* const kLayersHelp =
    "Also record the first K surfaces along each pixel-centre ray, K in [1, 64]: EXR channels "
    "hit<k>.Z hit<k>.T hit<k>.primID hit<k>.geomID for k = 0..K-1, nearest first "
    "(docs/layers.md)";

void addLayersOption(CLI::App& app, std::optional<int>& layers, const std::string& group) {
  CLI::Option* o = app.add_option("--layers", layers, kLayersHelp)->type_name("K");
  if (!group.empty()) o->group(group);
}

void addDeepOption(CLI::App& app, bool& deep, const std::string& group) {
  CLI::Option* o = app.add_flag("--deep", deep,
                                "With --layers K: write the layers as a deep EXR (samples Z, "
                                "ZBack, T, primID, geomID, nearest first) to <out stem>.deep.exr "
                                "instead of hit<k>.* channels (docs/layers.md)");
  if (!group.empty()) o->group(group);
}

void checkDeepHasLayers(bool deep, const std::optional<int>& layers) {
  if (deep && !layers)
    throw Error("--deep needs --layers K: the deep file holds the layered hits (docs/layers.md)");
}

void addRenderOptions(CLI::App& app, RenderOptions& o) {
  app.add_option("--aov", o.aovs,
                 cat("AOVs to compute: ", aovNameList(),
                     ", face.NAME, vertex.NAME (integer PLY properties)"))
      ->capture_default_str();
  app.add_option("--normal-frame", o.normalFrame,
                 "Frame of normal and shading-normal: world, opencv (x right, y down, z "
                 "forward) or opengl (x right, y up, z backwards), the camera's axes")
      ->capture_default_str();
  addLayersOption(app, o.layers);
  app.add_option("--packet", o.packet, "Rays per Embree call: 1, 4, 8 or 16")
      ->capture_default_str();
  app.add_option("--tile", o.tile, "Tile size in pixels: a multiple of 4 in [4, 4096]")
      ->capture_default_str();
  app.add_option("--threads", o.threads,
                 "Worker threads in [0, 4096] (0 = all cores): rendering, BVH builds and "
                 "OpenEXR's encoding of the files")
      ->capture_default_str();
}

RenderSettings RenderOptions::settings(int spp) const {
  RenderSettings s;
  s.packetWidth = packet;
  s.tileSize = tile;
  s.spp = spp;
  s.normalFrame = parseNormalFrame(normalFrame);
  validateRenderSettings(s);
  if (threads < 0 || threads > 4096)
    throw Error(cat("--threads ", threads, " must be in [0, 4096]"));
  return s;
}

AovSet RenderOptions::aovSet() const {
  AovSet set = parseAovSet(aovs);
  if (layers) {
    checkLayerCount(*layers, "--layers");
    set.layers = *layers;
  }
  return set;
}

struct ThreadLimitImpl {
  std::unique_ptr<tbb::global_control> control;
};

int resolvedThreads(int n) {
  return n > 0
             ? n
             : int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

ThreadLimit::ThreadLimit(int n) : impl_(std::make_unique<ThreadLimitImpl>()) {
  if (n > 0)
    impl_->control = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, size_t(n));
  threads_ = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

ThreadLimit::~ThreadLimit() = default;

}  // namespace aperture::app
