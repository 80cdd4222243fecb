#include "core/util/huge_pages.h"

#include <sys/mman.h>

#include <cstdint>

#include "core/util/sanitizers.h"

namespace aperture {

namespace {

constexpr uintptr_t kHugePage = uintptr_t(2) << 20;

uintptr_t roundUpToHugePage(uintptr_t a) { return (a + kHugePage - 1) & ~(kHugePage - 1); }

#ifndef APERTURE_ASAN
/// `length` bytes (a multiple of 2 MB) mapped on a 2 MB boundary: one huge page more is
/// mapped, and what lies before the boundary and after the buffer is unmapped again.
void* mapOnHugePageBoundary(size_t length) {
  void* raw =
      mmap(nullptr, length + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) throw std::bad_alloc();
  const uintptr_t first = reinterpret_cast<uintptr_t>(raw);
  const uintptr_t data = roundUpToHugePage(first);
  if (data > first) munmap(raw, data - first);
  const uintptr_t end = data + length, mappedEnd = first + length + kHugePage;
  if (mappedEnd > end) munmap(reinterpret_cast<void*>(end), mappedEnd - end);
  return reinterpret_cast<void*>(data);
}
#endif

}  // namespace

void adviseHugePages(const void* data, size_t bytes) {
#ifdef MADV_HUGEPAGE
  const uintptr_t begin = roundUpToHugePage(reinterpret_cast<uintptr_t>(data));
  const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(kHugePage - 1);
  if (data == nullptr || end <= begin) return;
  madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // a hint: errors ignored
#else
  (void)data, (void)bytes;
#endif
}

void* allocateLargeBuffer(size_t bytes) {
  if (bytes < kHugePage) return ::operator new(bytes);
#ifdef APERTURE_ASAN
  void* data = ::operator new(bytes, std::align_val_t(kHugePage));
  adviseHugePages(data, bytes);  // the rest of its last 2 MB may be another allocation's
#else
  const size_t length = roundUpToHugePage(bytes);
  void* data = mapOnHugePageBoundary(length);
  adviseHugePages(data, length);
#endif
  return data;
}

void deallocateLargeBuffer(void* data, size_t bytes) noexcept {
  if (bytes < kHugePage) {
    ::operator delete(data);
    return;
  }
#ifdef APERTURE_ASAN
  ::operator delete(data, std::align_val_t(kHugePage));
#else
  munmap(data, roundUpToHugePage(bytes));
#endif
}

}  // namespace aperture
