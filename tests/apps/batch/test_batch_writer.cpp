// The batch's writer threads (apps/batch/batch_writer.h): how many, what they cost in framebuffers,
// and that they write images in parallel, each exactly once.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <vector>

#include "apps/batch/batch_writer.h"

namespace aperture::app {
namespace batch_writer_test {

constexpr uint64_t kGiB = uint64_t(1) << 30;

TEST(BatchWriter, AsManyWritersAsRenderThreadsWithinAGibOfFramebuffers) {
  const uint64_t frame1080p = 1920 * 1080 * 16;  // depth and normal: 33 MB
  EXPECT_EQ(writerThreadsFor(2, frame1080p), 2);
  EXPECT_EQ(writerThreadsFor(64, frame1080p), 32);  // 32 x 33 MB fit in 1 GiB, 33 do not
  EXPECT_EQ(writerThreadsFor(64, kGiB / 3), 3);
  EXPECT_EQ(writerThreadsFor(64, 2 * kGiB), 1);  // one at least, however large
  EXPECT_EQ(writerThreadsFor(0, frame1080p), 1);
  EXPECT_EQ(writerThreadsFor(8, 0), 8);
}

TEST(BatchWriter, FramebuffersAliveAreTheRenderedTheWaitingAndOnePerWriter) {
  EXPECT_EQ(framebuffersAlive(0), 1);  // inline: each image written before the next renders
  EXPECT_EQ(framebuffersAlive(1), 3);
  EXPECT_EQ(framebuffersAlive(4), 6);
}

/// Counts the writes in progress and the most seen at once; a write waits (up to `patience`)
/// until `wanted` writes are in progress together, so with fewer threads than that
/// the most stays below it.
struct ConcurrentWrites {
  std::mutex mutex;
  std::condition_variable changed;
  int inProgress = 0, most = 0, wanted = 0;
  std::chrono::milliseconds patience{3000};  ///< how long a write waits for the others
  std::vector<int> writes;                   ///< per task index, how often it was written

  void write(ImageWriter::Task& task) {
    std::unique_lock<std::mutex> lock(mutex);
    ++writes[size_t(task.result - results)];
    most = std::max(most, ++inProgress);
    changed.notify_all();
    changed.wait_for(lock, patience, [&] { return most >= wanted; });
    --inProgress;
  }
  ImageResult* results = nullptr;
};

void runWriters(int threads, int wanted, int tasks, ConcurrentWrites& c) {
  std::vector<ImageResult> results(static_cast<size_t>(tasks));
  c.results = results.data();
  c.wanted = wanted;
  c.writes.assign(size_t(tasks), 0);
  ImageWriter writer([&](ImageWriter::Task& t) { c.write(t); }, threads, 1);
  for (ImageResult& r : results) writer.push({&r, RenderedView()});
  writer.finish();
}

TEST(BatchWriter, ThreadsWriteDifferentImagesAtOnceAndEachOnce) {
  ConcurrentWrites c;
  runWriters(3, 3, 12, c);
  EXPECT_EQ(c.most, 3);
  for (size_t k = 0; k < c.writes.size(); ++k) EXPECT_EQ(c.writes[k], 1) << "task " << k;
}

TEST(BatchWriter, OneThreadWritesOneImageAtATime) {
  // The check above can fail: one writer thread never has two writes in progress (each write
  // waits out its timeout for a second one that cannot come).
  ConcurrentWrites c;
  c.patience = std::chrono::milliseconds(300);
  runWriters(1, 2, 2, c);
  EXPECT_EQ(c.most, 1);
  EXPECT_EQ(c.writes, std::vector<int>({1, 1}));
}

TEST(BatchWriter, NoThreadWritesInline) {
  ConcurrentWrites c;
  std::vector<ImageResult> results(2);
  c.results = results.data();
  c.writes.assign(2, 0);
  ImageWriter writer([&](ImageWriter::Task& t) { c.write(t); }, 0, 1);
  writer.push({&results[0], RenderedView()});
  EXPECT_EQ(c.writes, std::vector<int>({1, 0}));  // written before push returned
  writer.push({&results[1], RenderedView()});
  EXPECT_EQ(c.writes, std::vector<int>({1, 1}));
}

}  // namespace batch_writer_test
}  // namespace aperture::app
