#include "apps/batch/batch_progress.h"

#include <unistd.h>

#include <cstdio>

namespace aperture::app {

double secondsSince(BatchClock::time_point t) {
  return std::chrono::duration<double>(BatchClock::now() - t).count();
}

std::string hms(double seconds) {
  const long s = long(seconds + 0.5);
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  return buf;
}

Progress::Progress(size_t total, bool quiet)
    : total_(total), quiet_(quiet), tty_(::isatty(STDERR_FILENO) == 1), start_(BatchClock::now()) {}

void Progress::startScene(size_t k, size_t count, const std::string& name, size_t images) {
  std::lock_guard<std::mutex> lock(mutex_);
  scene_ = "scene " + std::to_string(k) + "/" + std::to_string(count) + " ";
  if (quiet_) return;
  clearLine();
  drawn_ = false;
  std::fprintf(stderr, "aperture: scene %zu/%zu '%s': %zu images to render\n", k, count,
               name.c_str(), images);
  std::fflush(stderr);
}

void Progress::rendered(const ImageResult& r) {
  std::lock_guard<std::mutex> lock(mutex_);
  rays_ += r.rays;
}

void Progress::finished(const ImageResult& r) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++done_;
  if (quiet_) return;
  const double elapsed = secondsSince(start_);
  const double mrays = elapsed > 0 ? double(rays_) / elapsed * 1e-6 : 0;
  const double eta = done_ ? elapsed / double(done_) * double(total_ - done_) : 0;
  if (r.status == ImageStatus::Failed) {
    clearLine();
    std::fprintf(stderr, "aperture: %s failed: %s\n", imageLabel(*r.image).c_str(),
                 r.error.c_str());
  }
  if (tty_) {
    std::fprintf(stderr, "\r\033[K[%s%zu/%zu images] %.1f Mrays/s  elapsed %s  ETA %s",
                 scene_.c_str(), done_, total_, mrays, hms(elapsed).c_str(), hms(eta).c_str());
    drawn_ = true;
  } else if (r.status == ImageStatus::Ok) {
    std::fprintf(stderr,
                 "aperture: [%s%zu/%zu images] %s -> %s (render %.3f s, %.1f Mrays/s; write %.3f "
                 "s); elapsed %s, ETA %s\n",
                 scene_.c_str(), done_, total_, imageLabel(*r.image).c_str(),
                 r.image->output.c_str(), r.renderSeconds, r.mrays(), r.writeSeconds,
                 hms(elapsed).c_str(), hms(eta).c_str());
  }
  std::fflush(stderr);
}

void Progress::end() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (drawn_) std::fprintf(stderr, "\n");
  drawn_ = false;
}

void Progress::clearLine() {
  if (drawn_) std::fprintf(stderr, "\r\033[K");
}

}  // namespace aperture::app
