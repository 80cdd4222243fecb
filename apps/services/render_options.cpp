#include "apps/services/render_options.h"

#include <tbb/global_control.h>

#include "core/engine/layers.h"
#include "core/util/error.h"

namespace aperture::app {

void checkDeepHasLayers(bool deep, const std::optional<int>& layers) {
  if (deep && !layers)
    throw Error("--deep needs --layers K: the deep file holds the layered hits (docs/layers.md)");
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
