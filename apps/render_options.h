#pragma once
// The frame-loop flags (AOVs, packet width, tile size, threads) and the thread limit.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "core/render.h"

namespace aperture::app {

struct RenderOptions {
  std::string aovs = "color,depth";
  int packet = 16, tile = 32, threads = 0;
  std::string normalFrame = "world";  ///< --normal-frame
  RenderSettings settings(int spp) const;
};

void addRenderOptions(CLI::App& app, RenderOptions& o);

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
