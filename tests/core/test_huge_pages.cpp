#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/huge_pages.h"

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

/// The VmFlags of the mapping holding `address` (/proc/self/smaps), or "" when none does.
std::string mappingFlags(const void* address) {
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
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
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

}  // namespace
}  // namespace aperture
