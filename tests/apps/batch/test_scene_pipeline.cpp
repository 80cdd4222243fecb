// The load-ahead pipeline of a batch of several scenes (apps/batch/scene_pipeline.h): scene k+1
// loads while scene k renders, at most two scenes are alive, and a load's error reaches the
// caller after the load in flight.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "apps/batch/scene_pipeline.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// What the pipeline test records: events in order, scenes alive now and at most.
struct PipelineLog {
  std::mutex mutex;
  std::condition_variable loadedCv;
  std::vector<std::string> events;
  size_t loaded = 0;  ///< scenes whose load returned
  int alive = 0, peak = 0;
};

/// A scene of the pipeline test: counted while alive, its release logged.
struct TrackedScene {
  TrackedScene(size_t index, PipelineLog& log) : k(index), record(log) {
    std::lock_guard<std::mutex> lock(record.mutex);
    record.peak = std::max(record.peak, ++record.alive);
  }
  ~TrackedScene() {
    std::lock_guard<std::mutex> lock(record.mutex);
    --record.alive;
    record.events.push_back(cat("free ", k));
  }
  size_t k;
  PipelineLog& record;
};

size_t positionOf(const std::vector<std::string>& log, const std::string& event) {
  return size_t(std::find(log.begin(), log.end(), event) - log.begin());
}

}  // namespace

TEST(ScenePipeline, NextSceneLoadsWhileOneRendersAndAtMostTwoAreAlive) {
  constexpr size_t kScenes = 5;
  PipelineLog r;
  using Scene = std::unique_ptr<TrackedScene>;
  const std::function<Scene(size_t)> load = [&](size_t k) {
    {
      std::lock_guard<std::mutex> lock(r.mutex);
      r.events.push_back(cat("load ", k));
    }
    Scene s = std::make_unique<TrackedScene>(k, r);
    std::lock_guard<std::mutex> lock(r.mutex);
    r.loaded = std::max(r.loaded, k + 1);
    r.loadedCv.notify_all();
    return s;
  };
  const std::function<void(size_t, Scene&)> render = [&](size_t k, Scene& s) {
    ASSERT_EQ(s->k, k);
    std::unique_lock<std::mutex> lock(r.mutex);
    r.events.push_back(cat("render ", k));
    // Scene k's last image does not finish until scene k+1 is built: a pipeline that loads
    // the next scene only after rendering would never get there. (The timeout only turns such
    // a deadlock into a failure; nothing is timed.)
    if (k + 1 < kScenes) {
      EXPECT_TRUE(
          r.loadedCv.wait_for(lock, std::chrono::seconds(60), [&] { return r.loaded > k + 1; }))
          << "scene " << k + 1 << " was not loaded while scene " << k << " rendered";
    }
    r.events.push_back(cat("rendered ", k));
  };
  app::pipelineScenes(kScenes, load, render);
  const std::vector<std::string>& log = r.events;
  EXPECT_EQ(r.alive, 0);
  EXPECT_EQ(r.peak, 2);
  for (size_t k = 0; k < kScenes; ++k) {
    EXPECT_LT(positionOf(log, cat("load ", k)), positionOf(log, cat("render ", k)));
    EXPECT_LT(positionOf(log, cat("rendered ", k)), positionOf(log, cat("free ", k)));
    if (k + 1 < kScenes) {  // k+1 is built before k's render ends
      EXPECT_LT(positionOf(log, cat("load ", k + 1)), positionOf(log, cat("rendered ", k)));
    }
    if (k + 2 < kScenes) {  // k is released before k+2 starts loading
      EXPECT_LT(positionOf(log, cat("free ", k)), positionOf(log, cat("load ", k + 2)));
    }
  }
}

TEST(ScenePipeline, LoadErrorsPropagateAfterTheLoadInFlight) {
  const std::function<int(size_t)> load = [](size_t k) -> int {
    if (k == 2) throw Error("scene 2 is broken");
    return int(k);
  };
  std::vector<size_t> rendered;
  const std::function<void(size_t, int&)> render = [&](size_t k, int&) { rendered.push_back(k); };
  EXPECT_EQ(test::errorOf([&] { app::pipelineScenes(4, load, render); }), "scene 2 is broken");
  EXPECT_EQ(rendered, (std::vector<size_t>{0, 1}));
}
