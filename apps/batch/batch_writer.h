#pragma once
// `aperture batch`: writing rendered images (preview, dataset files, EXR) on writer threads
// that overlap the next image's rendering.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "apps/batch/batch_result.h"
#include "apps/services/view.h"
#include "core/exr/exr.h"

namespace aperture::app {

/// Writes `r`'s preview (when the job has one, with `preview`), its dataset files (with
/// `dataset`), its camera sidecar (with `cameraSidecar`) and then its EXR (header `meta`; none
/// unless `writeExr`) through writeViewOutputs, and sets r.status to Ok, or to Failed with
/// r.error when a write throws: a failed preview or dataset file leaves no new EXR, and
/// --resume renders it again.
void writeImageFiles(ImageResult& r, const RenderedView& view, const ExrMetadata& meta,
                     const ExrOptions& options, const PreviewOptions& preview,
                     bool cameraSidecar = false, bool writeExr = true,
                     const DatasetWriteOptions& dataset = {});

/// Writer threads for a batch rendering with `renderThreads` threads, whose framebuffers take
/// `frameBytes` each: as many as the render's threads, so that encoding (PNG and TIFF are one
/// thread a file) keeps up with a render on many cores, but no more than 1 GiB of framebuffers
/// being written, and at least one.
int writerThreadsFor(int renderThreads, uint64_t frameBytes);

/// Rendered images a batch's ImageWriter holds waiting for a writer thread (its capacity).
inline constexpr size_t kImagesWaiting = 1;

/// Framebuffers alive at once in a batch whose ImageWriter has `writers` threads (0: it
/// writes inline): the image being rendered, kImagesWaiting waiting and one in each writer
/// thread. --max-memory counts this many.
int framebuffersAlive(int writers);

/// Encodes and writes rendered images on `threads` threads, each taking the next image in
/// turn (images are written in parallel, each by one thread; every file of an image by that
/// thread, in order). It holds at most `capacity` images waiting, so the renderer blocks
/// instead of piling up framebuffers. With 0 threads, push() writes inline.
class ImageWriter {
 public:
  struct Task {
    ImageResult* result;
    RenderedView view;
  };
  /// Called on a writer thread, at once for different tasks on different threads.
  using WriteFn = std::function<void(Task&)>;

  ImageWriter(WriteFn write, int threads, size_t capacity);
  ~ImageWriter() { finish(); }
  ImageWriter(const ImageWriter&) = delete;
  ImageWriter& operator=(const ImageWriter&) = delete;

  /// Queues a rendered image (blocks while the queue is full).
  void push(Task task);
  /// Writes what is queued and stops the threads.
  void finish();

 private:
  void loop();

  WriteFn write_;
  size_t capacity_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<Task> queue_;
  bool closed_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace aperture::app
