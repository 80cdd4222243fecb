// Times writeNpz and readNpz (core/io/npz.h) on an archive past 4 GiB, where the zip64 records are
// needed: bench/npz_zip64.sh builds this against core/npz.cpp through libzip (c155488) and
// against the hand-written zip code (9bf1f53, kept), and runs both alternately.
//
//   npz_zip64 write PATH LAYOUT BYTES   writes BYTES of float32 data (i × 0.5) as
//                                       LAYOUT one: one member "data", shape (BYTES / 4,), or
//                                       LAYOUT many: members "m00000", ... of 1 MiB each
//   npz_zip64 read PATH LAYOUT BYTES    reads it back and checks every value
//
// Prints one line: the operation, layout, bytes, and the wall and CPU (user + system) seconds of
// the call alone (the write includes writeAtomically's fsync; the array is filled before the
// clock starts). The CPU seconds are the zip code's own work; the wall seconds of a write are
// mostly the disk's.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "core/io/npz.h"

namespace {

constexpr uint64_t kManyMemberBytes = 1u << 20;

/// Wall and CPU (user + system) seconds from a start point.
struct Clock {
  std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
  double cpu = cpuSeconds();

  static double cpuSeconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    const auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * t.tv_usec; };
    return seconds(u.ru_utime) + seconds(u.ru_stime);
  }
  /// "WALL CPU" seconds since construction.
  void print(const char* op, const std::string& kind, uint64_t bytes) const {
    const double w = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count();
    std::printf("%s %s %llu %.3f %.3f\n", op, kind.c_str(), static_cast<unsigned long long>(bytes),
                w, cpuSeconds() - cpu);
  }
};

/// The value at float index `i` of the whole data: exact in float32 for i < 2^24, then
/// periodic, so a member shifted or swapped shows up.
float valueAt(uint64_t i) { return float(i % (1u << 24)) * 0.5f; }

std::vector<aperture::NpzArray> layout(const std::string& kind, const std::vector<float>& data) {
  const uint64_t bytes = data.size() * sizeof(float);
  std::vector<aperture::NpzArray> arrays;
  if (kind == "one") {
    arrays.push_back({"data", "<f4", {data.size()}, data.data(), bytes});
    return arrays;
  }
  char name[32];
  for (uint64_t at = 0, k = 0; at < bytes; at += kManyMemberBytes, ++k) {
    const uint64_t n = std::min(kManyMemberBytes, bytes - at);
    std::snprintf(name, sizeof name, "m%05llu", static_cast<unsigned long long>(k));
    arrays.push_back({name, "<f4", {n / 4}, data.data() + at / 4, n});
  }
  return arrays;
}

int run(const std::string& op, const std::string& path, const std::string& kind, uint64_t bytes) {
  if ((kind != "one" && kind != "many") || bytes % 4 != 0) {
    std::fprintf(stderr, "npz_zip64: LAYOUT is one or many, BYTES a multiple of 4\n");
    return 2;
  }
  if (op == "write") {
    std::vector<float> data(bytes / 4);
    for (uint64_t i = 0; i < data.size(); ++i) data[i] = valueAt(i);
    const auto arrays = layout(kind, data);
    const Clock clock;
    aperture::writeNpz(path, arrays);
    clock.print("write", kind, bytes);
    return 0;
  }
  if (op == "read") {
    const Clock clock;
    const auto members = aperture::readNpz(path);
    clock.print("read", kind, bytes);
    uint64_t i = 0;
    for (const auto& [name, m] : members) {
      if (m.descr != "<f4") {
        std::fprintf(stderr, "npz_zip64: member %s has dtype %s\n", name.c_str(), m.descr.c_str());
        return 1;
      }
      const float* v = reinterpret_cast<const float*>(m.data.data());
      for (size_t k = 0; k < m.data.size() / 4; ++k, ++i)
        if (v[k] != valueAt(i)) {
          std::fprintf(stderr, "npz_zip64: member %s value %zu is %g, not %g\n", name.c_str(), k,
                       double(v[k]), double(valueAt(i)));
          return 1;
        }
    }
    if (i * 4 != bytes) {
      std::fprintf(stderr, "npz_zip64: %llu bytes read back, not %llu\n",
                   static_cast<unsigned long long>(i * 4), static_cast<unsigned long long>(bytes));
      return 1;
    }
    return 0;
  }
  std::fprintf(stderr, "npz_zip64: the operation is write or read\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: npz_zip64 write|read PATH one|many BYTES\n");
    return 2;
  }
  try {
    return run(argv[1], argv[2], argv[3], std::strtoull(argv[4], nullptr, 10));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "npz_zip64: %s\n", e.what());
    return 1;
  }
}
