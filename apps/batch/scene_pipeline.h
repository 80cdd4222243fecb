#pragma once
// `aperture batch` over many scenes: scene k renders while scene k+1 loads and builds on a
// background thread, and scene k is released before scene k+2 starts loading, so at most two
// scenes are alive at any time (what --max-memory budgets for).
#include <cstddef>
#include <functional>
#include <future>
#include <optional>

namespace aperture::app {

/// Calls render(k, scene k) for k = 0 .. count-1 in order, where scene k is what load(k)
/// returned. load(0) runs on the caller's thread; load(k+1) runs on a background thread while
/// render(k) runs. After render(k) returns, scene k is destroyed, then the caller waits for
/// scene k+1, and only then is load(k+2) started: two scenes at most are alive, the one
/// rendering and the one loading. An exception from load or render propagates (after the
/// background load in flight has finished); a caller that wants to go on past a scene that
/// fails to load catches inside `load` and returns a scene that says so.
template <class Scene>
void pipelineScenes(size_t count, const std::function<Scene(size_t)>& load,
                    const std::function<void(size_t, Scene&)>& render) {
  if (count == 0) return;
  std::optional<Scene> current(load(0));
  for (size_t k = 0; k < count; ++k) {
    std::future<Scene> next;
    if (k + 1 < count) next = std::async(std::launch::async, load, k + 1);
    render(k, *current);
    current.reset();
    if (next.valid()) current.emplace(next.get());
  }
}

}  // namespace aperture::app
