#pragma once
// `aperture batch`: progress on stderr (images done of total, Mrays/s, elapsed, ETA) and the
// clock helpers the batch uses for its timings.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>

#include "apps/batch/batch_result.h"

namespace aperture::app {

using BatchClock = std::chrono::steady_clock;

/// Seconds from `t` to now.
double secondsSince(BatchClock::time_point t);

/// A duration as m:ss or h:mm:ss.
std::string hms(double seconds);

/// Images done / total, Mrays/s, elapsed and ETA: one updating line on a terminal, a log line
/// per image otherwise, nothing with `quiet`. Safe to call from the render and writer threads.
class Progress {
 public:
  Progress(size_t total, bool quiet);

  /// Scene `k` (1-based) of `count` of a job with "scenes" starts rendering `images` images:
  /// logged, and shown as "scene k/count" in the progress line until the next one.
  void startScene(size_t k, size_t count, const std::string& name, size_t images);
  /// An image finished rendering (its rays count towards Mrays/s).
  void rendered(const ImageResult& r);
  /// An image is done (written or failed).
  void finished(const ImageResult& r);
  /// Ends the updating line, if one is drawn.
  void end();

 private:
  void clearLine();

  std::mutex mutex_;
  size_t total_, done_ = 0;
  uint64_t rays_ = 0;
  std::string scene_;  ///< "scene k/K " in a job with "scenes", else ""
  bool quiet_, tty_, drawn_ = false;
  BatchClock::time_point start_;
};

}  // namespace aperture::app
