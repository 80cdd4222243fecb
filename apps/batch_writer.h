#pragma once
// `aperture batch`: writing rendered images (EXR, then the preview) on a writer thread that
// overlaps the next image's rendering.
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

#include "apps/batch_result.h"
#include "apps/view.h"
#include "core/exr.h"

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

/// Encodes and writes rendered images. Threaded, it holds at most `capacity` images waiting,
/// so the renderer blocks instead of piling up framebuffers; unthreaded, push() writes inline.
class ImageWriter {
 public:
  struct Task {
    ImageResult* result;
    RenderedView view;
  };
  using WriteFn = std::function<void(Task&)>;

  ImageWriter(WriteFn write, bool threaded, size_t capacity);
  ~ImageWriter() { finish(); }
  ImageWriter(const ImageWriter&) = delete;
  ImageWriter& operator=(const ImageWriter&) = delete;

  /// Queues a rendered image (blocks while the queue is full).
  void push(Task task);
  /// Writes what is queued and stops the thread.
  void finish();

 private:
  void loop();

  WriteFn write_;
  size_t capacity_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<Task> queue_;
  bool closed_ = false;
  std::thread thread_;
};

}  // namespace aperture::app
