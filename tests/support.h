#pragma once
// Helpers shared by the test files.
#include <Imath/ImathVec.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "cameras/schema/params.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/io/image_codec.h"

namespace aperture::test {

/// A buffer of another allocator (a mesh's LargeBuffer) as a std::vector, to compare it with
/// expected values.
template <class T, class Allocator>
std::vector<T> asVector(const std::vector<T, Allocator>& v) {
  return {v.begin(), v.end()};
}

/// ../shared beside the project (absolute), as configured by CMake.
std::string sharedDir();
/// Path of a mesh under ../shared/meshes, or "" when ../shared is absent.
std::string sharedMesh(const std::string& relative);
/// A fresh empty directory under $TMPDIR, unique per test and process; removed when the test
/// passes, kept (and named on stderr) when it fails.
std::string scratchDir();
/// Path of the built `aperture` executable.
std::string apertureBinary();
/// Runs a shell command, returns its exit code (-1 if killed by a signal); stdout+stderr
/// go to *output when given.
int runCommand(const std::string& command, std::string* output = nullptr);
/// `s` in single quotes, as one shell word for runCommand (paths and specs of the tests hold no
/// single quote).
inline std::string quote(const std::string& s) { return "'" + s + "'"; }
/// What runMeasured saw of a child process.
struct Measured {
  int exitCode = -1;  ///< exit status, or -1 when a signal ended it
  int signal = 0;     ///< the signal that ended it, or 0
  double wallSeconds = 0;
  double cpuSeconds = 0;  ///< user + system time of the child
  long maxRssKb = 0;      ///< peak resident set of the child, KiB
  std::string output;     ///< stdout and stderr
};
/// Runs `command` through /bin/sh with `exec`, so the resource figures are the command's own.
Measured runMeasured(const std::string& command);

/// An image file read through the image codec (OpenImageIO), its samples converted to T.
template <class T>
struct DecodedImage {
  ImageFileInfo info;
  std::vector<T> samples;  ///< interleaved; empty when the file could not be read
};
/// Reads `path` (T: uint8_t, uint16_t, uint32_t or float), adding a test failure when it
/// cannot.
template <class T>
DecodedImage<T> readImageFile(const std::string& path) {
  static_assert(std::is_same_v<T, uint8_t> || std::is_same_v<T, uint16_t> ||
                std::is_same_v<T, uint32_t> || std::is_same_v<T, float>);
  const SampleType as = std::is_same_v<T, uint8_t>    ? SampleType::UInt8
                        : std::is_same_v<T, uint16_t> ? SampleType::UInt16
                        : std::is_same_v<T, uint32_t> ? SampleType::UInt32
                                                      : SampleType::Float;
  DecodedImage<T> image;
  std::vector<unsigned char> bytes;
  std::string error;
  if (!imageCodec().read(path, as, image.info, &bytes, error)) {
    ADD_FAILURE() << path << ": " << error;
    return image;
  }
  image.samples.resize(bytes.size() / sizeof(T));
  std::memcpy(image.samples.data(), bytes.data(), image.samples.size() * sizeof(T));
  return image;
}

/// The whole content of a file ("" when it cannot be read).
std::string readFile(const std::string& path);
/// Writes a file (binary-safe).
void writeFile(const std::string& path, const std::string& bytes);
bool fileExists(const std::string& path);
/// A JSON file, parsed (throws nlohmann::json::parse_error when it is missing or malformed).
nlohmann::json readJson(const std::string& path);

/// The AOVs (by name) whose size or pixel bits differ between a and b; "" when the two have the
/// same size, the same AOVs and bit-identical pixels in every one: the named AOVs, the shading
/// normal, every mesh-property AOV and the layers.
std::string differingAovs(const Framebuffer& a, const Framebuffer& b);
/// How far (pixels) a float32 world position P, projected by an EXR header's matrices, may
/// land from its pixel centre.
inline constexpr double kMaxPixelError = 1e-2;

/// Expects differingAovs(a, b) to be "", naming `what` when it is not.
inline void expectIdentical(const Framebuffer& a, const Framebuffer& b, const std::string& what) {
  EXPECT_EQ(differingAovs(a, b), "") << what;
}
/// Two renders of one frame that differ only in how misses are resolved without Embree (`on`
/// resolves more of them): every AOV and the traced, skipped and hit counts equal, some hits,
/// and `on` resolved nothing but misses.
inline void expectSameFrameFewerEmbreeRays(const Framebuffer& onFrame, const Framebuffer& offFrame,
                                           const RenderStats& on, const RenderStats& off,
                                           const std::string& what) {
  expectIdentical(onFrame, offFrame, what);
  EXPECT_EQ(on.raysTraced, off.raysTraced) << what;
  EXPECT_EQ(on.raysSkipped, off.raysSkipped) << what;
  EXPECT_EQ(on.hits, off.hits) << what;
  EXPECT_GT(on.hits, 0u) << what;
  EXPECT_LT(on.raysOutsideBox, on.raysTraced - on.hits + 1) << what;  // only misses
}
inline bool samePixels(const Framebuffer& a, const Framebuffer& b) {
  return differingAovs(a, b).empty();
}
/// Two renders of the same geometry by different paths (instances vs baked copies): the same
/// object per pixel, depth within 1e-4 relative, normals within 1e-3; at least minHits hits.
void expectSameGeometry(const Framebuffer& a, const Framebuffer& b, int minHits);

/// 64-bit FNV-1a over bytes, for golden hashes of buffers.
class Fnv1a {
 public:
  void add(const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t k = 0; k < bytes; ++k) h_ = (h_ ^ p[k]) * 0x100000001b3ull;
  }
  std::string hex() const;

 private:
  unsigned long long h_ = 0xcbf29ce484222325ull;
};

/// Camera parameters from command-line camera flags ("--camera thinlens --eye 0,0,5 ..."),
/// parsed exactly as `aperture render` parses them (the flags must give --at or --dir).
CameraParams cameraParamsFromFlags(const std::string& flags);

/// Calls f(i, j, P, Z, T) for every hit pixel of `fb` (finite Z; P world position, T ray
/// distance, NaN when `fb` has no distance AOV); returns their number.
int forEachHit(const Framebuffer& fb,
               const std::function<void(int, int, const Imath::V3d&, double, double)>& f);

/// The message of the aperture::Error `f` throws ("" when it throws none).
std::string errorOf(const std::function<void()>& f);

}  // namespace aperture::test

/// Skips the current test with a message when a ../shared mesh is missing.
#define APERTURE_REQUIRE_SHARED_MESH(var, rel)               \
  const std::string var = ::aperture::test::sharedMesh(rel); \
  if (var.empty())                                           \
  GTEST_SKIP() << "../shared/meshes/" rel                    \
                  " is absent (no ../shared "                \
                  "beside the project); this test needs it"
