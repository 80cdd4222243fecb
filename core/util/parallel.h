#pragma once
// The project's one parallel loop: tbb::parallel_for over [0, n) in chunks of `grain`, with
// ThreadSanitizer annotations for the fork and join edges. Debian's TBB is not instrumented,
// so without them TSan cannot see that a task runs after the caller wrote its inputs, nor
// that the caller resumes after every task finished.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>

#if defined(__SANITIZE_THREAD__)
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
extern "C" void AnnotateNewMemory(const char* file, int line, const volatile void* mem, long size);
#define APERTURE_TSAN_ACQUIRE(p) __tsan_acquire(p)
#define APERTURE_TSAN_RELEASE(p) __tsan_release(p)
// TBB's own code touches its task-tree nodes on the caller's stack after a task's last release
// (fold_tree), through atomics TSan cannot see; once tbb::parallel_for has returned, that
// stack below the caller's frame is dead, and its next user would be reported racing with
// them (tests/tsan.supp matches these reports only while TSan can still restore the worker's
// stack). Forgetting the dead region's access history removes them at the source: after each
// loop, and again before the next one forks, since a worker's last touch can land after the
// caller has resumed. The frame loop also forgets the stack below each tile's frame base
// (renderTile, core/engine/render.cpp), where reports of that kind kept appearing, and keeps its
// packets off the stack altogether (threadPackets).
#define APERTURE_TSAN_FORGET_STACK_BELOW(p) \
  AnnotateNewMemory(__FILE__, __LINE__, static_cast<const char*>(p) - (64 << 10), 64 << 10)
#else
#define APERTURE_TSAN_ACQUIRE(p) ((void)(p))
#define APERTURE_TSAN_RELEASE(p) ((void)(p))
#define APERTURE_TSAN_FORGET_STACK_BELOW(p) ((void)sizeof(p))  // p not evaluated
#endif

namespace aperture {

/// Calls body(begin, end) for consecutive chunks of at most `grain` indices of [0, n), in
/// parallel (simple partitioner: chunk boundaries do not depend on the thread count).
template <class Body>
void parallelFor(size_t n, size_t grain, const Body& body) {
  char fork = 0, join = 0;                  // addresses used only as TSan synchronisation objects
  APERTURE_TSAN_FORGET_STACK_BELOW(&fork);  // dead stack: the body may run on this thread
  APERTURE_TSAN_RELEASE(&fork);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, n, grain ? grain : 1),
      [&](const tbb::blocked_range<size_t>& r) {
        APERTURE_TSAN_ACQUIRE(&fork);
        body(r.begin(), r.end());
        APERTURE_TSAN_RELEASE(&join);
      },
      tbb::simple_partitioner());
  APERTURE_TSAN_ACQUIRE(&join);
  APERTURE_TSAN_FORGET_STACK_BELOW(&fork);
}

/// Calls body(c, begin, end) in parallel for numbered chunks of `chunk` indices of [0, n):
/// chunk c covers [c·chunk, min((c + 1)·chunk, n)). The boundaries do not depend on the thread
/// count (parallelFor's own ranges split in halves and need not fall on multiples of a grain),
/// so a caller can give chunk c its own result slot and combine the slots in order.
template <class Body>
void parallelForChunks(size_t n, size_t chunk, const Body& body) {
  const size_t chunks = (n + chunk - 1) / chunk;
  parallelFor(chunks, 1, [&](size_t first, size_t last) {
    for (size_t c = first; c < last; ++c) body(c, c * chunk, std::min(n, (c + 1) * chunk));
  });
}

}  // namespace aperture
