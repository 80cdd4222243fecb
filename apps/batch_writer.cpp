#include "apps/batch_writer.h"

#include <exception>

#include "core/image.h"

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

ImageWriter::ImageWriter(WriteFn write, bool threaded, size_t capacity)
    : write_(std::move(write)), capacity_(capacity) {
  if (threaded) thread_ = std::thread([this] { loop(); });
}

void ImageWriter::push(Task task) {
  if (!thread_.joinable()) {
    write_(task);
    return;
  }
  std::unique_lock<std::mutex> lock(mutex_);
  space_.wait(lock, [&] { return queue_.size() < capacity_; });
  queue_.push_back(std::move(task));
  ready_.notify_one();
}

void ImageWriter::finish() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
  }
  ready_.notify_one();
  thread_.join();
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
