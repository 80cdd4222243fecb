#include "apps/batch/batch_writer.h"

#include <algorithm>
#include <exception>

#include "core/io/image.h"

namespace aperture::app {

void writeImageFiles(ImageResult& r, const RenderedView& view, const ExrMetadata& meta,
                     const ExrOptions& options, const PreviewOptions& preview, bool cameraSidecar,
                     bool writeExr, const DatasetWriteOptions& dataset) {
  try {
    writeViewOutputs(view, meta, options, writeExr ? r.image->output : std::string(),
                     r.image->preview, preview, cameraSidecar, r.image->datasets, dataset);
    r.status = ImageStatus::Ok;
  } catch (const std::exception& e) {
    r.status = ImageStatus::Failed;
    r.error = e.what();
  }
}

int writerThreadsFor(int renderThreads, uint64_t frameBytes) {
  constexpr uint64_t kWrittenFramebufferBytes = uint64_t(1) << 30;
  const uint64_t byMemory = kWrittenFramebufferBytes / std::max<uint64_t>(frameBytes, 1);
  return int(
      std::max<uint64_t>(1, std::min<uint64_t>(uint64_t(std::max(renderThreads, 1)), byMemory)));
}

int framebuffersAlive(int writers) { return writers > 0 ? 1 + int(kImagesWaiting) + writers : 1; }

ImageWriter::ImageWriter(WriteFn write, int threads, size_t capacity)
    : write_(std::move(write)), capacity_(capacity) {
  for (int k = 0; k < threads; ++k) threads_.emplace_back([this] { loop(); });
}

void ImageWriter::push(Task task) {
  if (threads_.empty()) {
    write_(task);
    return;
  }
  std::unique_lock<std::mutex> lock(mutex_);
  space_.wait(lock, [&] { return queue_.size() < capacity_; });
  queue_.push_back(std::move(task));
  ready_.notify_one();
}

void ImageWriter::finish() {
  if (threads_.empty()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
  }
  ready_.notify_all();
  for (std::thread& t : threads_) t.join();
  threads_.clear();
}

void ImageWriter::loop() {
  for (;;) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [&] { return closed_ || !queue_.empty(); });
    if (queue_.empty()) return;
    Task task = std::move(queue_.front());
    queue_.pop_front();
    space_.notify_one();
    lock.unlock();
    write_(task);
  }
}

}  // namespace aperture::app
