#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/util/huge_pages.h"
#include "tests/support.h"

namespace aperture {
namespace {

// resizeOnHugePages is std::vector::resize: old elements kept, new ones value-initialised.
TEST(HugePages, ResizeKeepsOldElementsAndZeroesNewOnes) {
  std::vector<uint32_t> v = {7, 8, 9};
  resizeOnHugePages(v, size_t(3) << 20);  // 12 MB: whole 2 MB pages to advise
  ASSERT_EQ(v.size(), size_t(3) << 20);
  EXPECT_EQ(v[0], 7u);
  EXPECT_EQ(v[1], 8u);
  EXPECT_EQ(v[2], 9u);
  size_t nonZero = 0;
  for (size_t k = 3; k < v.size(); ++k) nonZero += v[k] != 0;
  EXPECT_EQ(nonZero, 0u);
  resizeOnHugePages(v, 2);  // shrinking is resize too
  EXPECT_EQ(v, (std::vector<uint32_t>{7, 8}));
}

TEST(HugePages, ReserveLeavesTheSize) {
  std::vector<float> v(5, 1.5f);
  reserveOnHugePages(v, size_t(1) << 22);
  EXPECT_EQ(v, std::vector<float>(5, 1.5f));
  EXPECT_GE(v.capacity(), size_t(1) << 22);
}

/// The line starting with `field` of the mapping holding `address` (/proc/self/smaps), or ""
/// when no mapping holds it.
std::string mappingField(const void* address, const std::string& field) {
  const uintptr_t a = reinterpret_cast<uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream range(line);
    if (range >> std::hex >> begin >> dash >> end && dash == '-') {
      inside = begin <= a && a < end;
      continue;
    }
    if (inside && line.rfind(field, 0) == 0) return line;
  }
  return "";
}

std::string mappingFlags(const void* address) { return mappingField(address, "VmFlags:"); }

/// Resident KiB of the mapping holding `address`, or -1 when no mapping holds it.
long residentKb(const void* address) {
  const std::string rss = mappingField(address, "Rss:");
  return rss.empty() ? -1 : std::stol(rss.substr(4));
}

// Where the kernel has transparent huge pages, the buffer's mapping carries the request
// (flag "hg", set by madvise whether or not a huge page was free). A no-op adviseHugePages
// fails here.
TEST(HugePages, TheNewBufferIsAdvisedWhereTheKernelHasThem) {
  std::vector<uint32_t> v;
  resizeOnHugePages(v, size_t(4) << 20);  // 16 MB
  const void* middle = v.data() + v.size() / 2;
  const std::string flags = mappingFlags(middle);
  ASSERT_FALSE(flags.empty()) << "no mapping in /proc/self/smaps holds the buffer";
  const bool kernelHasThp = std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled").good();
  EXPECT_EQ(flags.find(" hg") != std::string::npos, kernelHasThp) << flags;
}

// A LargeBuffer of 2 MB or more starts on a 2 MB boundary, so its first bytes are advised
// too: malloc's storage starts 16 bytes past a 4 KB page, and the whole 2 MB pages inside it
// begin up to 2 MB later (a plain std::allocator fails the alignment). Growing it moves it to
// new storage of the same kind, with the old elements; a small one needs no alignment.
TEST(HugePages, ALargeBufferStartsOnAHugePageBoundary) {
  constexpr uintptr_t kHugePage = uintptr_t(2) << 20;
  LargeBuffer<uint32_t> v;
  v.resize((kHugePage + 4096) / sizeof(uint32_t));  // one huge page and a bit
  EXPECT_EQ(reinterpret_cast<uintptr_t>(v.data()) % kHugePage, 0u);
  const bool kernelHasThp = std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled").good();
  const std::string flags = mappingFlags(v.data());
  ASSERT_FALSE(flags.empty()) << "no mapping in /proc/self/smaps holds the buffer";
  EXPECT_EQ(flags.find(" hg") != std::string::npos, kernelHasThp) << flags;
  v.front() = 11u;
  v.back() = 12u;
  const size_t n = v.size();
  v.resize(4 * n);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(v.data()) % kHugePage, 0u);
  EXPECT_EQ(v.front(), 11u);
  EXPECT_EQ(v[n - 1], 12u);
  LargeBuffer<uint32_t> small(7, 5u);
  EXPECT_EQ(test::asVector(small), std::vector<uint32_t>(7, 5u));
}

// A LargeBuffer grows without writing its new elements, so its pages stay untouched until
// their first writer (the parallel loaders) fills them. The same resize of a std::vector
// touches every page, which shows that the measure can tell them apart.
TEST(HugePages, ALargeBufferGrowsWithoutTouchingItsPages) {
  constexpr size_t kCount = size_t(16) << 20;  // 64 MB: a mapping of its own
  LargeBuffer<uint32_t> large;
  resizeOnHugePages(large, kCount);
  ASSERT_EQ(large.size(), kCount);
  EXPECT_LT(residentKb(large.data() + kCount / 2), 4096);
  std::vector<uint32_t> plain;
  resizeOnHugePages(plain, kCount);
  EXPECT_GE(residentKb(plain.data() + kCount / 2), long(kCount * sizeof(uint32_t) / 1024) - 4096);
  // Elements given a value are written as with std::vector.
  large.resize(kCount + 2, 7u);
  EXPECT_EQ(large[kCount], 7u);
  EXPECT_EQ(large[kCount + 1], 7u);
  LargeBuffer<float> copied = {1.5f, 2.5f};
  EXPECT_EQ(test::asVector(copied), (std::vector<float>{1.5f, 2.5f}));
}

}  // namespace
}  // namespace aperture
