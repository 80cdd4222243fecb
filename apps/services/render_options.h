#pragma once
// The frame-loop options (AOVs, packet width, tile size, threads) and the thread limit; their
// flags: apps/cli/render_flags.h.
#include <memory>
#include <optional>
#include <string>

#include "core/engine/render.h"

namespace aperture::app {

struct RenderOptions {
  std::string aovs = "color,depth";
  std::optional<int> layers;  ///< --layers K: the first K surfaces per pixel
  int packet = 16, tile = 32, threads = 0;
  std::string normalFrame = "world";  ///< --normal-frame
  RenderSettings settings(int spp) const;
  /// The AOVs of --aov and --layers; throws Error for a bad name or K.
  AovSet aovSet() const;
};

/// Throws Error naming --deep and --layers when --deep is given without --layers.
void checkDeepHasLayers(bool deep, const std::optional<int>& layers);

/// The threads a ThreadLimit(n) gives: n, or with n = 0 all the cores TBB may use.
int resolvedThreads(int n);

/// Limits TBB (and so Embree's builder) to n threads while alive; n = 0 keeps all cores.
class ThreadLimit {
 public:
  explicit ThreadLimit(int n);
  ~ThreadLimit();
  int threads() const { return threads_; }

 private:
  std::unique_ptr<struct ThreadLimitImpl> impl_;
  int threads_;
};

}  // namespace aperture::app
