#include "core/io/dataset_image.h"

#include <algorithm>
#include <bitset>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "core/aov/aov_table.h"
#include "core/io/atomic_file.h"
#include "core/io/image_codec.h"
#include "core/io/npy.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/little_endian.h"

namespace aperture {

namespace {

struct FormatEntry {
  DatasetFormat format;
  const char* name;
  const char* takes;  ///< what the format holds, for refusals
  bool listAovs;      ///< follow `takes` with the AOVs of the table it holds ("depth, distance")
  std::vector<std::string> extensions;
  bool imageCodec;  ///< encoded by the image codec (encodedByImageCodec)
};

const std::vector<FormatEntry>& formatTable() {
  static const std::vector<FormatEntry> table = {
      {DatasetFormat::Png16, "16-bit PNG", "one float channel: ", true, {".png"}, true},
      {DatasetFormat::Pfm, "PFM", "float AOVs of 1 or 3 channels: ", true, {".pfm"}, false},
      {DatasetFormat::Npy, "NumPy .npy", "every AOV (float32 or uint32)", false, {".npy"}, false},
      {DatasetFormat::Tiff,
       "float TIFF",
       "every AOV (float32 or uint32)",
       false,
       {".tif", ".tiff"},
       true},
  };
  return table;
}

const FormatEntry& entryOf(DatasetFormat format) {
  for (const FormatEntry& e : formatTable())
    if (e.format == format) return e;
  throw Error(cat("invalid dataset format value ", int(format)));
}

std::string layoutText(int channels, bool isFloat) {
  return cat(channels, " ", isFloat ? "float" : "uint32", " channel", channels == 1 ? "" : "s");
}

bool formatHolds(DatasetFormat format, int channels, bool isFloat) {
  switch (format) {
    case DatasetFormat::Png16:
      return isFloat && channels == 1;
    case DatasetFormat::Pfm:
      return isFloat && (channels == 1 || channels == 3);
    case DatasetFormat::Npy:
    case DatasetFormat::Tiff:
      return channels >= 1;
  }
  return false;
}

// --- Little-endian byte output (PFM with scale −1, NPY '<f4' / '<u4') -------------------------

/// `header`, then the rows of `image`, top to bottom or with `bottomRowFirst` bottom to top,
/// each row's samples interleaved as 4-byte little-endian words.
std::vector<unsigned char> headerAndRows(const std::string& header, const ImageView& image,
                                         bool bottomRowFirst) {
  const size_t perRow = size_t(image.width) * size_t(image.channels);
  const auto* samples = image.u32 ? reinterpret_cast<const unsigned char*>(image.u32)
                                  : reinterpret_cast<const unsigned char*>(image.f32);
  std::vector<unsigned char> out(header.size() + 4 * perRow * size_t(image.height));
  std::memcpy(out.data(), header.data(), header.size());
  unsigned char* at = out.data() + header.size();
  for (int k = 0; k < image.height; ++k, at += 4 * perRow) {
    const int row = bottomRowFirst ? image.height - 1 - k : k;
    storeLittleEndianWords(samples + 4 * perRow * size_t(row), perRow, at);
  }
  return out;
}

/// PFM (Netpbm's description): "PF" (3 channels) or "Pf" (1), "W H", the scale whose negative
/// sign means little-endian, each followed by one newline; then the raster, rows from the
/// bottom of the image to the top.
std::vector<unsigned char> encodePfm(const ImageView& image) {
  const std::string header =
      cat(image.channels == 3 ? "PF" : "Pf", "\n", image.width, " ", image.height, "\n-1.0\n");
  return headerAndRows(header, image, true);
}

/// NPY (the header of core/io/npy.h), then the array in C order.
std::vector<unsigned char> encodeNpy(const ImageView& image) {
  std::vector<uint64_t> shape = {uint64_t(image.height), uint64_t(image.width)};
  if (image.channels != 1) shape.push_back(uint64_t(image.channels));
  return headerAndRows(npyHeader(image.u32 ? "<u4" : "<f4", shape), image, false);
}

// --- Through the image codec (PNG16, TIFF), encoded in memory ------------------------------
// (then written by writeBytesAtomically, which checks every write)

/// round(value · scale) when it lies in [1, 65535]; 0 otherwise (+inf misses, and the
/// out-of-range values, NaN included, which are also counted).
std::vector<uint16_t> depthToUint16(const ImageView& image, double scale, size_t* outOfRange) {
  const size_t n = size_t(image.width) * size_t(image.height);
  std::vector<uint16_t> values(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const float v = image.f32[i];
    if (v == std::numeric_limits<float>::infinity()) continue;
    const double r = std::round(double(v) * scale);
    if (r >= 1.0 && r <= 65535.0)
      values[i] = uint16_t(r);
    else
      ++*outOfRange;
  }
  return values;
}

/// libpng's PNG_FILTER_UP flag (png.h): each row stored as its difference from the row above.
constexpr int kPngFilterUp = 0x20;

std::vector<unsigned char> encodePng16(const std::string& path, const ImageView& image,
                                       double scale, size_t* outOfRange) {
  const std::vector<uint16_t> values = depthToUint16(image, scale, outOfRange);
  ImageToEncode png{image.width, image.height, 1, SampleType::UInt16, values.data(), {}, {}};
  png.attributes = {
      {"ImageDescription", cat("aperture depth: round(value * ", scale, "), 0 = no valid value")}};
  // zlib level 6 (OpenImageIO's default), every row filtered by Up (libpng's PNG_FILTER_UP)
  // instead of libpng's choice among all five per row: 1.4-1.7x faster to encode on 1080p depth
  // for 2-5 % more bytes (bench/RESULTS.md, issue 13, thirteenth session).
  png.settings = {{"png:compressionLevel", 6}, {"png:filter", kPngFilterUp}};
  return encodeImage(path, png);
}

std::vector<unsigned char> encodeTiff(const std::string& path, const ImageView& image) {
  ImageToEncode tiff{
      image.width,
      image.height,
      image.channels,
      image.u32 ? SampleType::UInt32 : SampleType::Float,
      image.u32 ? static_cast<const void*>(image.u32) : static_cast<const void*>(image.f32),
      {{"compression", "zip"}},
      {}};
  return encodeImage(path, tiff);
}

// --- Reading back PFM and NPY ---------------------------------------------------------------

std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat("cannot open '", path, "' for reading"));
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Reads the next whitespace-separated header token at `pos` and the one whitespace byte
/// after it.
std::string headerToken(const std::string& bytes, size_t& pos, const std::string& path) {
  const size_t start = pos;
  while (pos < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
  if (pos == start || pos >= bytes.size()) throw Error(cat("'", path, "': truncated PFM header"));
  std::string token = bytes.substr(start, pos - start);
  ++pos;
  return token;
}

int positiveInt(const std::string& text, const std::string& what, const std::string& path) {
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || v <= 0 || v > (1L << 24))
    throw Error(cat("'", path, "': bad ", what, " '", text, "'"));
  return int(v);
}

/// Fills `count` values from `bytes` at `pos` in the given byte order.
void readValues(const std::string& bytes, size_t pos, size_t count, bool littleEndian,
                uint32_t* out) {
  for (size_t i = 0; i < count; ++i) {
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k) {
      const uint32_t b = static_cast<unsigned char>(bytes[pos + 4 * i + size_t(k)]);
      v |= b << (littleEndian ? 8 * k : 8 * (3 - k));
    }
    out[i] = v;
  }
}

void checkDataSize(const std::string& bytes, size_t pos, size_t count, const std::string& path) {
  if (bytes.size() - pos != 4 * count)
    throw Error(
        cat("'", path, "': ", bytes.size() - pos, " bytes of pixel data, expected ", 4 * count));
}

DatasetImage readPfm(const std::string& path, const std::string& bytes) {
  size_t pos = 0;
  const std::string id = headerToken(bytes, pos, path);
  if (id != "Pf" && id != "PF")
    throw Error(cat("'", path, "': not a PFM file (starts '", id, "')"));
  DatasetImage image;
  image.channels = id == "PF" ? 3 : 1;
  image.width = positiveInt(headerToken(bytes, pos, path), "PFM width", path);
  image.height = positiveInt(headerToken(bytes, pos, path), "PFM height", path);
  const std::string scaleText = headerToken(bytes, pos, path);
  const double scale = std::strtod(scaleText.c_str(), nullptr);
  if (!(scale != 0.0) || !std::isfinite(scale))
    throw Error(cat("'", path, "': bad PFM scale '", scaleText, "'"));
  const size_t rowValues = size_t(image.width) * size_t(image.channels);
  const size_t count = rowValues * size_t(image.height);
  checkDataSize(bytes, pos, count, path);
  image.f32.resize(count);
  std::vector<uint32_t> row(rowValues);
  // The file's first row is the bottom of the image.
  for (int fileRow = 0; fileRow < image.height; ++fileRow) {
    readValues(bytes, pos + 4 * rowValues * size_t(fileRow), rowValues, scale < 0, row.data());
    const size_t imageRow = size_t(image.height - 1 - fileRow);
    std::memcpy(&image.f32[imageRow * rowValues], row.data(), 4 * rowValues);
  }
  return image;
}

DatasetImage readNpy(const std::string& path, const std::string& bytes) {
  const NpyHeader header =
      parseNpyHeader(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), path);
  if (header.descr != "<f4" && header.descr != "<u4")
    throw Error(
        cat("'", path, "': NPY dtype '", header.descr, "' (only '<f4' and '<u4' are read)"));
  if (header.fortranOrder)
    throw Error(cat("'", path, "': NPY array in Fortran order (only C order is read)"));
  const std::vector<uint64_t>& dims = header.shape;
  if (dims.size() != 2 && dims.size() != 3)
    throw Error(cat("'", path, "': NPY shape (",
                    join(dims, ", ", [](uint64_t d) { return std::to_string(d); }),
                    ") is not (H, W) or (H, W, C)"));
  for (uint64_t d : dims) positiveInt(std::to_string(d), "NPY dimension", path);
  DatasetImage image;
  image.height = int(dims[0]);
  image.width = int(dims[1]);
  image.channels = dims.size() == 3 ? int(dims[2]) : 1;
  const size_t count = size_t(image.width) * size_t(image.height) * size_t(image.channels);
  checkDataSize(bytes, header.dataOffset, count, path);
  std::vector<uint32_t> values(count);
  readValues(bytes, header.dataOffset, count, true, values.data());
  if (header.descr == "<u4") {
    image.u32 = std::move(values);
  } else {
    image.f32.resize(count);
    std::memcpy(image.f32.data(), values.data(), 4 * count);
  }
  return image;
}

}  // namespace

std::optional<DatasetFormat> datasetFormatOf(const std::string& path) {
  const std::string extension = lowerExtension(path);
  for (const FormatEntry& e : formatTable())
    for (const std::string& known : e.extensions)
      if (extension == known) return e.format;
  return std::nullopt;
}

const char* datasetFormatName(DatasetFormat format) { return entryOf(format).name; }

bool encodedByImageCodec(DatasetFormat format) { return entryOf(format).imageCodec; }

const std::vector<std::string>& datasetExtensions() {
  static const std::vector<std::string> extensions = [] {
    std::vector<std::string> all;
    for (const FormatEntry& e : formatTable())
      all.insert(all.end(), e.extensions.begin(), e.extensions.end());
    return all;
  }();
  return extensions;
}

void checkDatasetAov(DatasetFormat format, const std::string& aovName, int channels, bool isFloat) {
  if (formatHolds(format, channels, isFloat)) return;
  const FormatEntry& e = entryOf(format);
  const std::string aovs =
      e.listAovs ? aovNamesWhere([&](int c, bool f) { return formatHolds(format, c, f); }) : "";
  throw Error(cat("AOV '", aovName, "' (", layoutText(channels, isFloat), ") cannot be written as ",
                  e.name, ", which takes ", e.takes, aovs, "; write it as .npy, .tif or .exr"));
}

void checkDatasetAov(DatasetFormat format, const std::string& aovName) {
  // The layout comes from aovView on a 1×1 framebuffer, so the AOV's channel count and type
  // have one definition (core/aov/framebuffer.cpp). parseAovSet rejects unknown names.
  const AovSet set = parseAovSet(aovName);
  const size_t count = std::bitset<32>(set.mask).count() + set.properties.size();
  if (count != 1 || aovListString(set) != aovName)
    throw Error(cat("'", aovName, "' is not one AOV: a dataset file holds exactly one (",
                    aovListString(set), " were named)"));
  const ImageView layout = aovView(Framebuffer(1, 1, set), aovName);
  checkDatasetAov(format, aovName, layout.channels, layout.f32 != nullptr);
}

namespace {

/// The file's bytes in `format` (PNG16 counts its out-of-range values into `stats`).
std::vector<unsigned char> encodedImage(const std::string& path, DatasetFormat format,
                                        const ImageView& image, double scale,
                                        DatasetWriteStats& stats) {
  switch (format) {
    case DatasetFormat::Png16:
      return encodePng16(path, image, scale, &stats.outOfRange);
    case DatasetFormat::Tiff:
      return encodeTiff(path, image);
    case DatasetFormat::Pfm:
      return encodePfm(image);
    case DatasetFormat::Npy:
      return encodeNpy(image);
  }
  throw Error(cat("invalid dataset format value ", int(format)));
}

}  // namespace

DatasetWriteStats writeDatasetImage(const std::string& path, DatasetFormat format,
                                    const ImageView& image, const std::string& aovName,
                                    const DatasetWriteOptions& options) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0)
    throw Error(cat("cannot write '", path, "': empty image (", image.width, "x", image.height, "x",
                    image.channels, ")"));
  if ((image.f32 == nullptr) == (image.u32 == nullptr))
    throw Error(cat("cannot write '", path, "': the image view of AOV '", aovName,
                    "' must hold exactly one of float or uint32 data"));
  try {
    checkDatasetAov(format, aovName, image.channels, image.f32 != nullptr);
  } catch (const Error& e) {
    throw Error(cat("cannot write '", path, "': ", e.what()));
  }
  const double scale = options.depthScale;
  if (format == DatasetFormat::Png16 && !(scale > 0.0 && std::isfinite(scale)))
    throw Error(
        cat("cannot write '", path, "': depth scale ", scale, " (must be positive and finite)"));

  DatasetWriteStats stats;
  try {
    const std::vector<unsigned char> bytes = encodedImage(path, format, image, scale, stats);
    writeBytesAtomically(path, bytes.data(), bytes.size());
  } catch (const Error& e) {
    const std::string message = e.what();
    // writeBytesAtomically's errors already name the path.
    if (message.find(path) != std::string::npos) throw;
    throw Error(cat("cannot write '", path, "': ", message));
  }
  return stats;
}

DatasetImage readDatasetImage(const std::string& path) {
  const std::optional<DatasetFormat> format = datasetFormatOf(path);
  if (format != DatasetFormat::Pfm && format != DatasetFormat::Npy)
    throw Error(cat("cannot read '", path, "': readDatasetImage reads .pfm and .npy files"));
  const std::string bytes = readWholeFile(path);
  return *format == DatasetFormat::Pfm ? readPfm(path, bytes) : readNpy(path, bytes);
}

}  // namespace aperture
