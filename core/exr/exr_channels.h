#pragma once
// EXR files of named channels without an AOV behind them: the LiDAR range images
// (core/points/range_image.h), beams × columns, one channel per field.
#include <cstdint>
#include <string>
#include <vector>

namespace aperture {

/// One channel of an image: float32 (`floats`) or uint32 (`uints`) values, width × height in
/// row-major order; exactly one of the two is filled.
struct ExrChannel {
  std::string name;
  std::vector<float> floats;
  std::vector<uint32_t> uints;
  bool isUint() const { return floats.empty() && !uints.empty(); }
};

/// Writes `channels` (FLOAT or UINT, each width × height values) to `path` atomically, ZIP
/// compressed, with `strings` as string attributes. Throws Error naming the file for a channel
/// of the wrong size, an empty or repeated name, no channel, or an I/O failure.
void writeExrChannels(const std::string& path, int width, int height,
                      const std::vector<ExrChannel>& channels,
                      const std::vector<std::pair<std::string, std::string>>& strings = {});

/// Reads every channel of `path` back (FLOAT and HALF as floats, UINT as uints), in the file's
/// order (OpenEXR sorts channels by name). Throws Error naming the file.
std::vector<ExrChannel> readExrChannels(const std::string& path, int* width = nullptr,
                                        int* height = nullptr);

}  // namespace aperture
