// Dataset image writers (core/io/dataset_image.h): 16-bit PNG depth, PFM, NPY and float TIFF.
// Every file is read back by a reader independent of the writer: OpenImageIO and a hand
// parse of the PNG header for PNG16 (written through OpenImageIO), byte-level parses of the
// PFM and NPY layouts written here from the format descriptions, OpenImageIO for TIFF.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include "core/io/dataset_image.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace dataset_image_test {

using test::fileExists;
using test::readFile;
using test::scratchDir;

constexpr float kInf = std::numeric_limits<float>::infinity();

float floatFromBits(uint32_t bits) {
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}
uint32_t bitsOf(float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return bits;
}

/// A quiet NaN with a payload, to show values are copied as bits, not as numbers.
const float kNanPayload = floatFromBits(0x7fc12345u);

uint32_t littleEndianAt(const std::string& bytes, size_t pos) {
  uint32_t v = 0;
  for (int k = 0; k < 4; ++k)
    v |= uint32_t(static_cast<unsigned char>(bytes[pos + size_t(k)])) << (8 * k);
  return v;
}
uint32_t bigEndianAt(const std::string& bytes, size_t pos) {
  uint32_t v = 0;
  for (int k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(bytes[pos + size_t(k)]);
  return v;
}

/// Every value of an asymmetric W×H×C image is distinct, so a flipped or transposed layout
/// cannot match; some carry special bit patterns.
std::vector<float> asymmetricFloats(int w, int h, int c) {
  std::vector<float> v(size_t(w) * size_t(h) * size_t(c));
  for (size_t k = 0; k < v.size(); ++k) v[k] = 0.25f + float(k) * 1.5f;
  v[0] = kNanPayload;
  v[1] = -0.0f;
  v[2] = kInf;
  v[3] = -kInf;
  v[4] = floatFromBits(0x00000001u);  // the smallest subnormal
  return v;
}

void expectSameBits(const std::vector<float>& a, const std::vector<float>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) EXPECT_EQ(bitsOf(a[k]), bitsOf(b[k])) << "value " << k;
}

TEST(DatasetFormat, ByExtensionCaseInsensitive) {
  EXPECT_EQ(datasetFormatOf("a/b.PNG"), DatasetFormat::Png16);
  EXPECT_EQ(datasetFormatOf("x.pfm"), DatasetFormat::Pfm);
  EXPECT_EQ(datasetFormatOf("x.npy"), DatasetFormat::Npy);
  EXPECT_EQ(datasetFormatOf("x.tif"), DatasetFormat::Tiff);
  EXPECT_EQ(datasetFormatOf("x.TIFF"), DatasetFormat::Tiff);
  EXPECT_EQ(datasetFormatOf("x.exr"), std::nullopt);
  EXPECT_EQ(datasetFormatOf("x.png.exr"), std::nullopt);
  EXPECT_EQ(datasetFormatOf("dir.png/x"), std::nullopt);
  EXPECT_EQ(datasetExtensions(),
            (std::vector<std::string>{".png", ".pfm", ".npy", ".tif", ".tiff"}));
}

/// The refusal message of checkDatasetAov (format, name), or "" when it accepts.
std::string refusal(DatasetFormat format, const std::string& aov) {
  try {
    checkDatasetAov(format, aov);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(DatasetFormat, RefusesWhatAFormatCannotHold) {
  const std::string png = refusal(DatasetFormat::Png16, "normal");
  EXPECT_NE(png.find("'normal'"), std::string::npos) << png;
  EXPECT_NE(png.find("16-bit PNG"), std::string::npos) << png;
  EXPECT_NE(png.find("one float channel: depth, distance"), std::string::npos) << png;
  EXPECT_NE(refusal(DatasetFormat::Png16, "primid"), "");
  EXPECT_NE(refusal(DatasetFormat::Png16, "face.object_id"), "");
  EXPECT_NE(refusal(DatasetFormat::Png16, "color"), "");
  const std::string pfmIds = refusal(DatasetFormat::Pfm, "geomid");
  EXPECT_NE(pfmIds.find("PFM"), std::string::npos) << pfmIds;
  const std::string pfmColor = refusal(DatasetFormat::Pfm, "color");
  EXPECT_NE(pfmColor.find("4 float channels"), std::string::npos) << pfmColor;

  EXPECT_EQ(refusal(DatasetFormat::Png16, "depth"), "");
  EXPECT_EQ(refusal(DatasetFormat::Png16, "distance"), "");
  EXPECT_EQ(refusal(DatasetFormat::Pfm, "normal"), "");
  EXPECT_EQ(refusal(DatasetFormat::Pfm, "depth"), "");
  for (DatasetFormat f : {DatasetFormat::Npy, DatasetFormat::Tiff})
    for (const char* aov : {"color", "depth", "normal", "position", "primid", "geomid",
                            "shading-normal", "face.object_id", "vertex.label"})
      EXPECT_EQ(refusal(f, aov), "") << datasetFormatName(f) << " " << aov;

  // Unknown names and lists are refused too.
  EXPECT_NE(refusal(DatasetFormat::Npy, "dpeth").find("did you mean"), std::string::npos);
  EXPECT_NE(refusal(DatasetFormat::Npy, "depth,normal").find("exactly one"), std::string::npos);
}

// --- 16-bit PNG -----------------------------------------------------------------------------

struct PngHeader {
  uint32_t width = 0, height = 0;
  int bitDepth = 0, colourType = 0;
};

/// The IHDR chunk, parsed by hand from the PNG layout (signature, then length, "IHDR", width,
/// height, bit depth, colour type, all big-endian).
PngHeader parseIhdr(const std::string& bytes) {
  const std::string signature("\x89PNG\r\n\x1a\n", 8);
  EXPECT_EQ(bytes.substr(0, 8), signature);
  EXPECT_EQ(bigEndianAt(bytes, 8), 13u);
  EXPECT_EQ(bytes.substr(12, 4), "IHDR");
  PngHeader h;
  h.width = bigEndianAt(bytes, 16);
  h.height = bigEndianAt(bytes, 20);
  h.bitDepth = static_cast<unsigned char>(bytes[24]);
  h.colourType = static_cast<unsigned char>(bytes[25]);
  return h;
}

/// The PNG16 rule, written out independently of the writer: round(z · scale) when it is in
/// [1, 65535], else 0; everything but +inf that gives 0 is out of range.
uint16_t expectedPng16(float z, double scale, size_t* outOfRange) {
  if (z == kInf) return 0;
  const double r = std::nearbyint(double(z) * scale);  // no value here lies on a .5 tie
  if (!(r >= 1 && r <= 65535)) {
    ++*outOfRange;
    return 0;
  }
  return uint16_t(r);
}

std::vector<uint16_t> readUint16WithOiio(const std::string& path, int* w, int* h) {
  const test::DecodedImage<uint16_t> png = test::readImageFile<uint16_t>(path);
  *w = png.info.width;
  *h = png.info.height;
  EXPECT_EQ(png.info.channels, 1);
  EXPECT_EQ(png.info.type, SampleType::UInt16);
  return png.samples;
}

TEST(DatasetPng16, MillimetresWithZeroForMissesAndOutOfRange) {
  const std::string path = scratchDir() + "/depth.png";
  // 4 wide, 3 high, asymmetric: a row or column swap changes the decoded values.
  const std::vector<float> depth = {
      1.2344f,  kInf,  0.0004f,     65.5354f,  // 1234, miss, rounds to 0, the largest value
      65.5356f, -1.0f, kNanPayload, 0.0f,      // 65536, negative, NaN, zero: out of range
      0.0021f,  2.0f,  -kInf,       30.0006f,  // 2, 2000, −inf: out of range, 30001
  };
  const ImageView view{4, 3, 1, depth.data(), nullptr};
  const DatasetWriteStats stats = writeDatasetImage(path, DatasetFormat::Png16, view, "depth");

  size_t expectedOut = 0;
  std::vector<uint16_t> expected;
  for (float z : depth) expected.push_back(expectedPng16(z, 1000.0, &expectedOut));
  EXPECT_EQ(stats.outOfRange, expectedOut);
  EXPECT_EQ(expectedOut, 6u);  // 0.0004, 65.5356, -1, NaN, 0, -inf
  EXPECT_EQ(expected[0], 1234);
  EXPECT_EQ(expected[3], 65535);

  const PngHeader ihdr = parseIhdr(readFile(path));
  EXPECT_EQ(ihdr.width, 4u);
  EXPECT_EQ(ihdr.height, 3u);
  EXPECT_EQ(ihdr.bitDepth, 16);
  EXPECT_EQ(ihdr.colourType, 0);  // greyscale, no alpha

  int w = 0, h = 0;
  EXPECT_EQ(readUint16WithOiio(path, &w, &h), expected);
  EXPECT_EQ(w, 4);
  EXPECT_EQ(h, 3);
}

/// The chunks of a PNG file after its signature, in order: type and data (by hand from the
/// PNG layout: length, type, data, CRC).
std::vector<std::pair<std::string, std::string>> pngChunks(const std::string& bytes) {
  std::vector<std::pair<std::string, std::string>> chunks;
  for (size_t at = 8; at + 12 <= bytes.size();) {
    const size_t length = bigEndianAt(bytes, at);
    chunks.emplace_back(bytes.substr(at + 4, 4), bytes.substr(at + 8, length));
    at += 12 + length;
  }
  return chunks;
}

/// The filter type that starts each row of a 16-bit grey PNG's image data: its IDAT chunks
/// joined and inflated by zlib, rows of 1 + 2·width bytes.
std::vector<int> rowFilterTypes(const std::string& bytes, int width, int height) {
  std::string compressed;
  for (const auto& [type, data] : pngChunks(bytes))
    if (type == "IDAT") compressed += data;
  const size_t stride = 1 + 2 * size_t(width);
  std::vector<unsigned char> rows(stride * size_t(height));
  uLongf size = uLongf(rows.size());
  EXPECT_EQ(uncompress(rows.data(), &size, reinterpret_cast<const Bytef*>(compressed.data()),
                       uLong(compressed.size())),
            Z_OK);
  EXPECT_EQ(size, rows.size());
  std::vector<int> filters;
  for (int row = 0; row < height; ++row) filters.push_back(rows[size_t(row) * stride]);
  return filters;
}

TEST(DatasetPng16, EveryRowUpFilteredAndNoSettingStored) {
  // Depths that climb along each row, each row offset from the one above by a different step:
  // libpng's own choice filters every row by Sub here (shown by hand by leaving out the
  // writer's setting: 64 of 64 rows Sub), so the check below fails when the setting is lost;
  // passed as a string attribute instead, it lands in a tEXt chunk and fails the last check.
  const int w = 96, h = 64;
  std::vector<float> depth(size_t(w) * size_t(h));
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j)
      depth[size_t(i) * size_t(w) + size_t(j)] =
          1.0f + 0.013f * float(j) + 0.1f * float((i * 7919) % 17);
  const std::string path = scratchDir() + "/up.png";
  writeDatasetImage(path, DatasetFormat::Png16, ImageView{w, h, 1, depth.data(), nullptr}, "depth");
  const std::string bytes = readFile(path);
  const std::vector<int> filters = rowFilterTypes(bytes, w, h);
  ASSERT_EQ(filters.size(), size_t(h));
  for (int row = 0; row < h; ++row) EXPECT_EQ(filters[size_t(row)], 2) << "row " << row;  // Up
  // The one text chunk is the description; encoder settings are not written into the file.
  for (const auto& [type, data] : pngChunks(bytes)) {
    if (type == "tEXt" || type == "zTXt" || type == "iTXt") {
      EXPECT_EQ(data.substr(0, data.find('\0')), "Description") << data;
    }
  }
}

TEST(DatasetPng16, DepthScaleAndBadScales) {
  const std::string dir = scratchDir();
  const std::vector<float> depth = {0.2f, 1.0f, 13.1f, kInf, 0.5f, 3.0f};
  const ImageView view{3, 2, 1, depth.data(), nullptr};
  DatasetWriteOptions tum;
  tum.depthScale = 5000;  // TUM RGB-D: 5000 units per metre
  const DatasetWriteStats stats =
      writeDatasetImage(dir + "/tum.png", DatasetFormat::Png16, view, "depth", tum);
  EXPECT_EQ(stats.outOfRange, 0u);  // 13.1 m · 5000 = 65500 still fits; the miss is not counted
  int w = 0, h = 0;
  const std::vector<uint16_t> values = readUint16WithOiio(dir + "/tum.png", &w, &h);
  EXPECT_EQ(values, (std::vector<uint16_t>{1000, 5000, 65500, 0, 2500, 15000}));

  for (double bad : {0.0, -1.0, std::nan(""), double(kInf)}) {
    DatasetWriteOptions o;
    o.depthScale = bad;
    const std::string path = dir + "/bad.png";
    try {
      writeDatasetImage(path, DatasetFormat::Png16, view, "depth", o);
      ADD_FAILURE() << "depth scale " << bad << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("depth scale"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fileExists(path));
  }
}

// --- PFM ------------------------------------------------------------------------------------

/// Parses the three header lines of a PFM by hand; returns the offset of the raster.
size_t parsePfmHeader(const std::string& bytes, std::string* id, int* w, int* h, double* scale) {
  std::istringstream in(bytes);
  in >> *id >> *w >> *h >> *scale;
  EXPECT_TRUE(in.good());
  // Exactly one whitespace byte follows the scale.
  return size_t(in.tellg()) + 1;
}

void checkPfm(int channels) {
  const int w = 3, h = 2;
  const std::vector<float> values = asymmetricFloats(w, h, channels);
  const std::string path = scratchDir() + "/image.pfm";
  writeDatasetImage(path, DatasetFormat::Pfm, {w, h, channels, values.data(), nullptr},
                    channels == 3 ? "normal" : "depth");

  const std::string bytes = readFile(path);
  std::string id;
  int fw = 0, fh = 0;
  double scale = 0;
  const size_t raster = parsePfmHeader(bytes, &id, &fw, &fh, &scale);
  EXPECT_EQ(id, channels == 3 ? "PF" : "Pf");
  EXPECT_EQ(fw, w);
  EXPECT_EQ(fh, h);
  EXPECT_EQ(scale, -1.0);  // negative: little-endian
  EXPECT_EQ(bytes.substr(0, raster), cat(id, "\n", w, " ", h, "\n-1.0\n"));
  ASSERT_EQ(bytes.size(), raster + 4 * values.size());
  // The file's first row is the image's bottom row (row h − 1). The image's rows differ, so
  // writing row 0 first fails here.
  const size_t rowValues = size_t(w) * size_t(channels);
  for (int fileRow = 0; fileRow < h; ++fileRow)
    for (size_t k = 0; k < rowValues; ++k)
      EXPECT_EQ(littleEndianAt(bytes, raster + 4 * (size_t(fileRow) * rowValues + k)),
                bitsOf(values[size_t(h - 1 - fileRow) * rowValues + k]))
          << "file row " << fileRow << " value " << k;

  const DatasetImage back = readDatasetImage(path);
  EXPECT_EQ(back.width, w);
  EXPECT_EQ(back.height, h);
  EXPECT_EQ(back.channels, channels);
  EXPECT_TRUE(back.u32.empty());
  expectSameBits(back.f32, values);
}

TEST(DatasetPfm, GreyRoundTripsBitExactlyBottomRowFirst) { checkPfm(1); }
TEST(DatasetPfm, ColourRoundTripsBitExactlyBottomRowFirst) { checkPfm(3); }

TEST(DatasetPfm, ReaderHonoursBigEndianScale) {
  // A big-endian PFM (positive scale) written here by hand: 2×1, values 1.0 and −2.5.
  std::string bytes = "Pf\n2 1\n1.0\n";
  for (float v : {1.0f, -2.5f})
    for (int k = 3; k >= 0; --k) bytes.push_back(char((bitsOf(v) >> (8 * k)) & 0xffu));
  const std::string path = scratchDir() + "/big.pfm";
  test::writeFile(path, bytes);
  const DatasetImage back = readDatasetImage(path);
  EXPECT_EQ(back.f32, (std::vector<float>{1.0f, -2.5f}));
}

// --- NPY ------------------------------------------------------------------------------------

struct NpyParsed {
  std::string dict;
  size_t dataOffset = 0;
};

/// The NPY 1.0 preamble parsed by hand: magic, version, little-endian header length.
NpyParsed parseNpyPreamble(const std::string& bytes) {
  EXPECT_EQ(bytes.substr(0, 6), std::string("\x93NUMPY", 6));
  EXPECT_EQ(bytes[6], 1);
  EXPECT_EQ(bytes[7], 0);
  const size_t len = size_t(static_cast<unsigned char>(bytes[8])) |
                     size_t(static_cast<unsigned char>(bytes[9])) << 8;
  NpyParsed p{bytes.substr(10, len), 10 + len};
  EXPECT_EQ(p.dataOffset % 64, 0u) << "the data must start on a 64-byte boundary";
  EXPECT_EQ(p.dict.back(), '\n');
  return p;
}

TEST(DatasetNpy, FloatRoundTripsBitExactlyInCOrder) {
  for (int channels : {1, 3, 4}) {
    const int w = 3, h = 2;
    const std::vector<float> values = asymmetricFloats(w, h, channels);
    const std::string path = scratchDir() + "/a.npy";
    const char* aov = channels == 1 ? "depth" : channels == 3 ? "normal" : "color";
    writeDatasetImage(path, DatasetFormat::Npy, {w, h, channels, values.data(), nullptr}, aov);
    const std::string bytes = readFile(path);
    const NpyParsed p = parseNpyPreamble(bytes);
    const std::string shape = channels == 1 ? "(2, 3)" : cat("(2, 3, ", channels, ")");
    EXPECT_EQ(p.dict.substr(0, p.dict.find('}') + 1),
              cat("{'descr': '<f4', 'fortran_order': False, 'shape': ", shape, ", }"));
    EXPECT_EQ(p.dict.find_first_not_of(' ', p.dict.find('}') + 1), p.dict.size() - 1);
    ASSERT_EQ(bytes.size(), p.dataOffset + 4 * values.size());
    // C order: row 0 first, then columns, then channels.
    for (size_t k = 0; k < values.size(); ++k)
      EXPECT_EQ(littleEndianAt(bytes, p.dataOffset + 4 * k), bitsOf(values[k])) << k;
    const DatasetImage back = readDatasetImage(path);
    EXPECT_EQ(back.width, w);
    EXPECT_EQ(back.height, h);
    EXPECT_EQ(back.channels, channels);
    expectSameBits(back.f32, values);
  }
}

TEST(DatasetNpy, IdsAreUint32) {
  const std::vector<uint32_t> ids = {0, 1, 7, kInvalidId, 0x01020304u, 42};
  const std::string path = scratchDir() + "/ids.npy";
  writeDatasetImage(path, DatasetFormat::Npy, {2, 3, 1, nullptr, ids.data()}, "primid");
  const std::string bytes = readFile(path);
  const NpyParsed p = parseNpyPreamble(bytes);
  EXPECT_EQ(p.dict.rfind("{'descr': '<u4', 'fortran_order': False, 'shape': (3, 2), }", 0), 0u)
      << p.dict;
  for (size_t k = 0; k < ids.size(); ++k)
    EXPECT_EQ(littleEndianAt(bytes, p.dataOffset + 4 * k), ids[k]);
  const DatasetImage back = readDatasetImage(path);
  EXPECT_EQ(back.u32, ids);
  EXPECT_TRUE(back.f32.empty());
}

// --- TIFF -----------------------------------------------------------------------------------

TEST(DatasetTiff, FloatAndIdsReadBackByOpenImageIo) {
  const std::string dir = scratchDir();
  const std::vector<float> normal = asymmetricFloats(4, 3, 3);
  writeDatasetImage(dir + "/n.tif", DatasetFormat::Tiff, {4, 3, 3, normal.data(), nullptr},
                    "normal");
  const std::vector<uint32_t> ids = {5, kInvalidId, 0, 1, 2, 3};
  writeDatasetImage(dir + "/ids.tiff", DatasetFormat::Tiff, {3, 2, 1, nullptr, ids.data()},
                    "face.object_id");

  const test::DecodedImage<float> back = test::readImageFile<float>(dir + "/n.tif");
  EXPECT_EQ(back.info.width, 4);
  EXPECT_EQ(back.info.height, 3);
  EXPECT_EQ(back.info.channels, 3);
  EXPECT_EQ(back.info.type, SampleType::Float);
  ASSERT_EQ(back.samples.size(), normal.size());
  expectSameBits(back.samples, normal);

  const test::DecodedImage<uint32_t> backIds = test::readImageFile<uint32_t>(dir + "/ids.tiff");
  EXPECT_EQ(backIds.info.type, SampleType::UInt32);
  EXPECT_EQ(backIds.samples, ids);
}

// --- Failures leave no file -----------------------------------------------------------------

TEST(DatasetWrite, RefusalsAndFailuresLeaveNoFile) {
  const std::string dir = scratchDir();
  const std::vector<float> normal(3 * 4, 0.5f);
  const std::string png = dir + "/n.png";
  try {
    writeDatasetImage(png, DatasetFormat::Png16, {2, 2, 3, normal.data(), nullptr}, "normal");
    ADD_FAILURE() << "normal written as PNG16";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'normal'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fileExists(png));

  const std::string missingDir = dir + "/no/such/dir/d.npy";
  EXPECT_THROW(
      writeDatasetImage(missingDir, DatasetFormat::Npy, {2, 2, 1, normal.data(), nullptr}, "depth"),
      Error);
  EXPECT_FALSE(fileExists(missingDir));
  EXPECT_TRUE(std::filesystem::is_empty(dir));

  EXPECT_THROW(writeDatasetImage(dir + "/e.npy", DatasetFormat::Npy,
                                 {0, 2, 1, normal.data(), nullptr}, "depth"),
               Error);
  EXPECT_THROW(
      writeDatasetImage(dir + "/e.npy", DatasetFormat::Npy, {2, 2, 1, nullptr, nullptr}, "depth"),
      Error);
}

TEST(DatasetRead, BadFilesNameThePath) {
  const std::string dir = scratchDir();
  const std::pair<const char*, std::string> cases[] = {
      {"/short.pfm", "Pf\n2 2\n-1.0\n1234"},
      {"/magic.pfm", "P6\n2 2\n255\n"},
      {"/magic.npy", "NUMPY"},
      {"/dtype.npy", std::string("\x93NUMPY\x01\x00\x20\x00", 10) +
                         "{'descr': '<f8', 'fortran_order': False, 'shape': (1, 1), }\n"},
  };
  for (const auto& [name, bytes] : cases) {
    const std::string path = dir + name;
    test::writeFile(path, bytes);
    try {
      readDatasetImage(path);
      ADD_FAILURE() << name << " was read";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
}

}  // namespace dataset_image_test
}  // namespace aperture
