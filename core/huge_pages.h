#pragma once
// Large buffers on transparent huge pages. A freshly allocated buffer costs a page fault and a
// kernel page clear per 4 KB page on first touch: for a mesh's vertex and index buffers that is
// a large, serial part of a binary PLY load (the crown's 63 MB: 10-15 ms on 4 KB pages, ~3 ms
// on 2 MB pages, of a ~45 ms load). Where the kernel offers transparent huge pages only on request
// (`madvise` mode, Debian's default), asking for them before the first touch takes that cost
// down; elsewhere the request changes nothing.
#include <cstddef>
#include <vector>

namespace aperture {

/// Asks the kernel to back the whole 2 MB pages inside [data, data + bytes) with transparent
/// huge pages (madvise MADV_HUGEPAGE). Only a hint: ignored where unsupported or refused.
void adviseHugePages(const void* data, size_t bytes);

/// v.reserve(n), new storage advised onto huge pages before anything touches it.
template <class T>
void reserveOnHugePages(std::vector<T>& v, size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  adviseHugePages(v.data(), v.capacity() * sizeof(T));
}

/// v.resize(n), new storage advised onto huge pages before the resize first touches it.
/// Elements are value-initialised and the old ones kept, as std::vector::resize does.
template <class T>
void resizeOnHugePages(std::vector<T>& v, size_t n) {
  reserveOnHugePages(v, n);
  v.resize(n);
}

}  // namespace aperture
