#pragma once
// The project's one parallel loop: tbb::parallel_for over [0, n) in chunks of `grain`, with
// ThreadSanitizer annotations for the fork and join edges. Debian's TBB is not instrumented,
// so without them TSan cannot see that a task runs after the caller wrote its inputs, nor
// that the caller resumes after every task finished.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

#if defined(__SANITIZE_THREAD__)
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#define APERTURE_TSAN_ACQUIRE(p) __tsan_acquire(p)
#define APERTURE_TSAN_RELEASE(p) __tsan_release(p)
#else
#define APERTURE_TSAN_ACQUIRE(p) ((void)(p))
#define APERTURE_TSAN_RELEASE(p) ((void)(p))
#endif

namespace aperture {

/// Calls body(begin, end) for consecutive chunks of at most `grain` indices of [0, n), in
/// parallel (simple partitioner: chunk boundaries do not depend on the thread count).
template <class Body>
void parallelFor(size_t n, size_t grain, const Body& body) {
  char fork = 0, join = 0;  // addresses used only as TSan synchronisation objects
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
}

}  // namespace aperture
