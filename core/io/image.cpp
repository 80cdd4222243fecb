#include "core/io/image.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include "core/aov/aov_table.h"
#include "core/io/atomic_file.h"
#include "core/io/image_codec.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/sampling.h"

namespace aperture {

namespace {

uint8_t toByte(double v) { return uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); }

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1].
double srgbEncode(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

/// Its inverse: the linear value of an sRGB-encoded value in [0, 1].
double srgbDecode(double encoded) {
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

/// RGB bytes of a preview, 3 per pixel, and what they show (for ImageDescription).
struct PreviewImage {
  std::vector<uint8_t> rgb;
  std::string description;
};

void setPixel(std::vector<uint8_t>& rgb, size_t i, const std::array<uint8_t, 3>& c) {
  for (int k = 0; k < 3; ++k) rgb[3 * i + size_t(k)] = c[size_t(k)];
}

/// Every pixel starts as the background; the AOV's painters overwrite the hits.
std::vector<uint8_t> backgroundPixels(size_t n) {
  std::vector<uint8_t> rgb(3 * n);
  for (size_t i = 0; i < n; ++i) setPixel(rgb, i, kPreviewBackground);
  return rgb;
}

PreviewImage colorPreview(const Framebuffer& fb, const std::vector<float>& rgba) {
  const size_t n = fb.pixelCount();
  PreviewImage out{std::vector<uint8_t>(3 * n), "color over the background"};
  double background[3];
  for (int c = 0; c < 3; ++c) background[c] = srgbDecode(kPreviewBackground[size_t(c)] / 255.0);
  for (size_t i = 0; i < n; ++i) {
    const double uncovered = 1.0 - std::clamp(double(rgba[4 * i + 3]), 0.0, 1.0);
    for (int c = 0; c < 3; ++c)
      out.rgb[3 * i + size_t(c)] =
          toByte(srgbEncode(rgba[4 * i + size_t(c)] + uncovered * background[c]));
  }
  return out;
}

/// options.depthRange, else the nearest and farthest finite depth of the image (NaN, NaN when
/// it has none).
glm::dvec2 depthRangeOf(const std::vector<float>& depth, const PreviewOptions& options) {
  if (options.depthRange) return *options.depthRange;
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (float z : depth)
    if (std::isfinite(z)) lo = std::min(lo, z), hi = std::max(hi, z);
  if (lo > hi) return glm::dvec2(std::numeric_limits<double>::quiet_NaN());
  return {lo, hi};
}

/// `x` with 9 significant digits ("0.45", not cat's "0.45000000000000001").
std::string shortNumber(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", x);
  return text;
}

/// A grey preview of one float channel ("depth (Z): ..."), misses (non-finite) the background.
PreviewImage greyPreview(const AovRow& row, const std::vector<float>& depth,
                         const PreviewOptions& options) {
  const glm::dvec2 range = depthRangeOf(depth, options);
  const double nearZ = range.x, farZ = range.y;
  const std::string what = cat(row.name, " (", row.exrChannels.front(), "): ");
  PreviewImage out{backgroundPixels(depth.size()),
                   std::isnan(nearZ)
                       ? cat(what, "no finite ", row.name)
                       : cat(what, shortNumber(nearZ), " white to ", shortNumber(farZ), " black (",
                             options.depthRange ? "fixed" : "this image's", " range)")};
  for (size_t i = 0; i < depth.size(); ++i) {
    const double z = depth[i];
    if (!std::isfinite(z)) continue;
    // Near is bright, far dark, as a display value (not sRGB-encoded); constant depth is white.
    const uint8_t g = toByte(farZ > nearZ ? (farZ - z) / (farZ - nearZ) : 1.0);
    setPixel(out.rgb, i, {g, g, g});
  }
  return out;
}

PreviewImage normalPreview(const AovRow& row, const std::vector<float>& normal) {
  PreviewImage out{backgroundPixels(normal.size() / 3), cat(row.name, " (N * 0.5 + 0.5)")};
  for (size_t i = 0; i < normal.size() / 3; ++i) {
    const float* n = &normal[3 * i];
    if (n[0] == 0.0f && n[1] == 0.0f && n[2] == 0.0f) continue;  // a miss
    setPixel(out.rgb, i,
             {toByte(n[0] * 0.5 + 0.5), toByte(n[1] * 0.5 + 0.5), toByte(n[2] * 0.5 + 0.5)});
  }
  return out;
}

/// A colour per ID: three bytes of its hash, each lifted into [96, 255] so that no ID is as
/// dark as the background. The ID is salted so that ID 0 (hash32(0) = 0) is not grey.
std::array<uint8_t, 3> idColor(uint32_t id) {
  const uint32_t h = hash32(id ^ 0x9e3779b9u);
  std::array<uint8_t, 3> c;
  for (int k = 0; k < 3; ++k) c[size_t(k)] = uint8_t(96 + ((h >> (8 * k)) & 0xffu) * 159u / 255u);
  return c;
}

PreviewImage idPreview(const std::vector<uint32_t>& ids, const char* name) {
  PreviewImage out{backgroundPixels(ids.size()), cat(name, " (hashed colours)")};
  for (size_t i = 0; i < ids.size(); ++i)
    if (ids[i] != kInvalidId) setPixel(out.rgb, i, idColor(ids[i]));
  return out;
}

/// The preview of `fb` (its buffers must have the framebuffer's size).
PreviewImage previewPixels(const Framebuffer& fb, const PreviewOptions& options,
                           const std::string& path) {
  const size_t n = fb.pixelCount();
  const AovMask shown = previewAov(fb.aovs);
  const AovRow* row = nullptr;
  for (const AovRow& r : aovTable())
    if (r.bit == shown && shown != 0) row = &r;
  if (!row)
    throw Error(cat("cannot write preview '", path, "': none of the AOVs ", aovListString(fb.aovs),
                    " can be previewed (", aovListString(previewableAovMask()), " can)"));
  if (valueCount(fb, *row) == size_t(row->channels()) * n) {
    switch (row->preview) {
      case PreviewRule::Color:
        return colorPreview(fb, floatPixels(fb, *row));
      case PreviewRule::Grey:
        return greyPreview(*row, floatPixels(fb, *row), options);
      case PreviewRule::Normal:
        return normalPreview(*row, floatPixels(fb, *row));
      case PreviewRule::HashedId:
        return idPreview(uintPixels(fb, *row), row->exrChannels.front().c_str());
      case PreviewRule::None:
        break;
    }
  }
  throw Error(cat("cannot write preview '", path, "': the framebuffer's buffers are incomplete"));
}

/// The file `path` would hold, encoded by the image codec for its extension.
std::vector<unsigned char> encodeRgb8(const std::string& path, int width, int height,
                                      const PreviewImage& image) {
  ImageToEncode rgb;
  rgb.width = width, rgb.height = height, rgb.channels = 3;
  rgb.type = SampleType::UInt8;
  rgb.pixels = image.rgb.data();
  rgb.attributes = {{"oiio:ColorSpace", "sRGB"},
                    {"ImageDescription", "aperture preview: " + image.description}};
  return encodeImage(path, rgb);
}

}  // namespace

AovMask previewableAovMask() {
  AovMask mask = 0;
  for (const AovRow& row : aovTable())
    if (row.preview != PreviewRule::None) mask |= row.bit;
  return mask;
}

namespace {
/// The previewable rows in order of preference: AovRow::previewFirst ones, then the others,
/// each in table order.
std::vector<const AovRow*> previewRows() {
  std::vector<const AovRow*> rows;
  for (bool first : {true, false})
    for (const AovRow& row : aovTable())
      if (row.preview != PreviewRule::None && row.previewFirst == first) rows.push_back(&row);
  return rows;
}
}  // namespace

Aov previewAov(AovMask aovs) {
  for (const AovRow* row : previewRows())
    if ((aovs & row->bit) != 0) return Aov(row->bit);
  return Aov(0);
}

std::string previewableAovText() {
  std::vector<std::string> names;
  for (const AovRow* row : previewRows()) names.push_back(row->name);
  std::string text = names.empty() ? "" : names.front();
  for (size_t k = 1; k < names.size(); ++k)
    text += (k == 1 ? ", else " : k + 1 == names.size() ? " or " : ", ") + names[k];
  return text;
}

const std::vector<PreviewFormat>& previewFormats() {
  static const std::vector<PreviewFormat> formats = {
      {"PNG", {".png"}}, {"JPEG", {".jpg", ".jpeg"}}, {"TIFF", {".tif", ".tiff"}},
      {"BMP", {".bmp"}}, {"Targa", {".tga"}},         {"PPM", {".ppm"}},
  };
  return formats;
}

const std::vector<std::string>& previewExtensions() {
  static const std::vector<std::string> extensions = [] {
    std::vector<std::string> all;
    for (const PreviewFormat& f : previewFormats())
      all.insert(all.end(), f.extensions.begin(), f.extensions.end());
    return all;
  }();
  return extensions;
}

void writePreview(const std::string& path, const Framebuffer& fb, const PreviewOptions& options) {
  const std::string extension = lowerExtension(path);
  const std::vector<std::string>& known = previewExtensions();
  if (std::find(known.begin(), known.end(), extension) == known.end())
    throw Error(cat("cannot write preview '", path, "': unknown preview extension '", extension,
                    "' (supported: ", join(known, " "), ")"));
  if (fb.width <= 0 || fb.height <= 0)
    throw Error(cat("cannot write preview '", path, "': empty framebuffer"));
  const PreviewImage image = previewPixels(fb, options, path);
  std::vector<unsigned char> bytes;
  try {
    bytes = encodeRgb8(path, fb.width, fb.height, image);
  } catch (const Error& e) {
    throw Error(cat("cannot write '", path, "': ", e.what()));
  }
  writeBytesAtomically(path, bytes.data(), bytes.size());
}

namespace {

/// Mean relative depth error over pixels finite in both with Zref != 0.
double depthRelativeError(const std::vector<float>& test, const std::vector<float>& ref) {
  double sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < test.size(); ++i) {
    if (!std::isfinite(test[i]) || !std::isfinite(ref[i]) || ref[i] == 0.0f) continue;
    sum += std::abs(double(test[i]) - ref[i]) / std::abs(double(ref[i]));
    ++count;
  }
  return count ? sum / double(count) : 0.0;
}

}  // namespace

ImageDiff compareFramebuffers(const Framebuffer& test, const Framebuffer& reference, double peak) {
  if (test.width != reference.width || test.height != reference.height)
    throw Error(cat("cannot compare images of different sizes: ", test.width, "x", test.height,
                    " vs reference ", reference.width, "x", reference.height));
  const size_t n = test.pixelCount();
  const bool color = test.has(kAovColor) && reference.has(kAovColor) && test.rgba.size() == 4 * n &&
                     reference.rgba.size() == 4 * n;
  const bool depth = test.has(kAovDepth) && reference.has(kAovDepth) && test.depth.size() == n &&
                     reference.depth.size() == n;
  if (!color && !depth)
    throw Error("cannot compare images: they share neither a color nor a depth AOV");

  // Depth is copied so that misses (+inf in both) compare equal instead of giving
  // inf − inf = NaN.
  std::vector<float> a, b;
  const float* pa = test.rgba.data();
  const float* pb = reference.rgba.data();
  if (!color) {
    a = test.depth;
    b = reference.depth;
    for (size_t i = 0; i < n; ++i)
      if (std::isinf(a[i]) && a[i] == b[i]) a[i] = b[i] = 0.0f;
    pa = a.data();
    pb = b.data();
  }
  SampleDifference d;
  std::string error;
  if (!imageCodec().compare(test.width, test.height, color ? 4 : 1, pa, pb, d, error))
    throw Error(cat("image comparison failed: ", error));

  ImageDiff diff;
  diff.rmse = d.rms;
  diff.maxError = d.max;
  diff.meanError = d.mean;
  diff.psnr =
      diff.rmse > 0 ? 20.0 * std::log10(peak / diff.rmse) : std::numeric_limits<double>::infinity();
  if (test.has(kAovPrimId) && reference.has(kAovPrimId) && test.primId.size() == n &&
      reference.primId.size() == n && n > 0) {
    size_t differ = 0;
    for (size_t i = 0; i < n; ++i) differ += test.primId[i] != reference.primId[i];
    diff.primIdMismatch = double(differ) / double(n);
  }
  if (depth) diff.depthRelError = depthRelativeError(test.depth, reference.depth);
  return diff;
}

}  // namespace aperture
