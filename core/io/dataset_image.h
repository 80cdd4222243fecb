#pragma once
// Single-AOV image files in the formats datasets use: 16-bit PNG depth (ScanNet, TUM,
// Redwood), PFM (MVSNet), NumPy .npy and float TIFF. One AOV per file; the EXR (core/exr/exr.h)
// stays the multi-channel format.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/aov/framebuffer.h"

namespace aperture {

enum class DatasetFormat {
  Png16,  ///< .png: uint16 grey, round(value · depthScale), 0 for a miss or out of range
  Pfm,    ///< .pfm: float32, little-endian (scale −1), rows bottom to top ("Pf" or "PF")
  Npy,    ///< .npy: NumPy format 1.0, '<f4' or '<u4', C order, shape (H, W) or (H, W, C)
  Tiff,   ///< .tif/.tiff: float32 (or uint32 ids) through OpenImageIO
};

/// The format of a dataset output path by its extension (case-insensitive), or nothing
/// (.exr and unknown extensions).
std::optional<DatasetFormat> datasetFormatOf(const std::string& path);
const char* datasetFormatName(DatasetFormat format);  ///< "16-bit PNG", "PFM", ...
/// Whether the format is written through the image codec (core/io/image_codec.h), which a job
/// then loads: PNG and TIFF are, PFM and NPY are written here.
bool encodedByImageCodec(DatasetFormat format);
/// The extensions (lower case, with the dot) datasetFormatOf knows.
const std::vector<std::string>& datasetExtensions();

/// Throws Error("AOV 'normal' cannot be written as 16-bit PNG (...)") before any rendering
/// when a format cannot hold an AOV: PNG16 takes one float channel (depth, distance); PFM
/// takes float with 1 or 3 channels; NPY and TIFF take every AOV. `aovName` as in aovView,
/// `channels` and `isFloat` its layout.
void checkDatasetAov(DatasetFormat format, const std::string& aovName, int channels, bool isFloat);
/// The same from the AOV's name alone (layout of the fixed AOVs; properties are 1-channel UINT).
void checkDatasetAov(DatasetFormat format, const std::string& aovName);

struct DatasetWriteOptions {
  double depthScale = 1000.0;  ///< PNG16: units per scene unit (1000: millimetres per metre)
};

struct DatasetWriteStats {
  /// PNG16: values other than +inf (a miss) whose round(value · depthScale) is not in
  /// [1, 65535] (negative, zero, too far, NaN, −inf); written as 0 like the misses.
  size_t outOfRange = 0;
};

/// Writes `image` to `path` in `format`, atomically (core/io/atomic_file.h: a failure leaves no
/// file). Throws Error naming the file and the reason (and checkDatasetAov's refusals for
/// the view's layout, with `aovName` in the message).
DatasetWriteStats writeDatasetImage(const std::string& path, DatasetFormat format,
                                    const ImageView& image, const std::string& aovName,
                                    const DatasetWriteOptions& options = {});

/// Reads back a PFM or NPY this module wrote (for tests and tools): float32 or uint32
/// values, row 0 at the top, with their shape. Throws Error naming the file.
struct DatasetImage {
  int width = 0, height = 0, channels = 1;
  std::vector<float> f32;
  std::vector<uint32_t> u32;
};
DatasetImage readDatasetImage(const std::string& path);

}  // namespace aperture
