#pragma once
// Large buffers on transparent huge pages. A freshly allocated buffer costs a page fault and a
// kernel page clear per 4 KB page on first touch: for a mesh's vertex and index buffers that is
// a large, serial part of a binary PLY load (the crown's 63 MB: 10-15 ms on 4 KB pages, ~3 ms
// on 2 MB pages, of a ~45 ms load). Where the kernel offers transparent huge pages only on request
// (`madvise` mode, Debian's default), asking for them before the first touch takes that cost
// down; elsewhere the request changes nothing. A LargeBuffer goes further: its storage starts on
// a 2 MB boundary, so all of it can be on huge pages (malloc's start 16 bytes past a 4 KB page,
// which leaves up to 2 MB at each end on 4 KB pages: half of the bathroom's index buffer), and
// its resize does not write the new elements, so the pages are first touched by the (parallel)
// code that fills them.
#include <cstddef>
#include <limits>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace aperture {

/// Storage of `bytes` bytes for a LargeBuffer. From 2 MB up it is mapped on a 2 MB boundary,
/// its length rounded up to whole 2 MB pages, and advised onto huge pages; smaller storage
/// comes from operator new. Under AddressSanitizer all of it comes from the aligned operator
/// new, which ASan checks to the byte, and is advised the same way.
void* allocateLargeBuffer(size_t bytes);
/// Gives back storage from allocateLargeBuffer(bytes).
void deallocateLargeBuffer(void* data, size_t bytes) noexcept;

/// The allocator of LargeBuffer: storage from allocateLargeBuffer, and growing a vector
/// (resize) leaves the new elements default-initialised, which for numbers means unwritten: a
/// buffer that its first writer fills in parallel is then touched once, by that writer, instead
/// of first zeroed by one thread. Elements given a value (resize(n, v), assign, insert) are
/// written as ever.
template <class T>
struct LargeBufferAllocator {
  using value_type = T;
  LargeBufferAllocator() = default;
  template <class U>
  LargeBufferAllocator(const LargeBufferAllocator<U>&) noexcept {}
  T* allocate(size_t n) {
    if (n > std::numeric_limits<size_t>::max() / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(allocateLargeBuffer(n * sizeof(T)));
  }
  void deallocate(T* p, size_t n) noexcept { deallocateLargeBuffer(p, n * sizeof(T)); }
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const LargeBufferAllocator<U>&) const noexcept {
    return true;
  }
  template <class U>
  bool operator!=(const LargeBufferAllocator<U>&) const noexcept {
    return false;
  }
};

/// A large numeric buffer on huge pages whose resize does not write the new elements
/// (LargeBufferAllocator).
template <class T>
using LargeBuffer = std::vector<T, LargeBufferAllocator<T>>;

/// Asks the kernel to back the whole 2 MB pages inside [data, data + bytes) with transparent
/// huge pages (madvise MADV_HUGEPAGE). Only a hint: ignored where unsupported or refused.
void adviseHugePages(const void* data, size_t bytes);

/// v.reserve(n), new storage advised onto huge pages before anything touches it (a
/// LargeBuffer's allocator has advised it already).
template <class T, class A>
void reserveOnHugePages(std::vector<T, A>& v, size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  if constexpr (!std::is_same_v<A, LargeBufferAllocator<T>>)
    adviseHugePages(v.data(), v.capacity() * sizeof(T));
}

/// v.resize(n), new storage advised onto huge pages before the resize first touches it.
/// The old elements are kept and the new ones initialised as the vector's resize does: zeroed
/// in a std::vector, left unwritten in a LargeBuffer.
template <class T, class A>
void resizeOnHugePages(std::vector<T, A>& v, size_t n) {
  reserveOnHugePages(v, n);
  v.resize(n);
}

}  // namespace aperture
