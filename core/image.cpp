#include "core/image.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"

namespace aperture {

namespace {

uint8_t toByte(double v) { return uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); }

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1].
double srgbEncode(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

/// The extension of `path` (".png"), or "" when it has none.
std::string extensionOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  if (dot == (slash == std::string::npos ? 0 : slash + 1)) return "";
  return path.substr(dot);
}

/// Pixels (channels interleaved) of the preview of `fb`.
std::vector<uint8_t> previewPixels(const Framebuffer& fb, const std::string& path, int* channels) {
  const size_t n = fb.pixelCount();
  std::vector<uint8_t> out;
  if (fb.has(kAovColor) && fb.rgba.size() == 4 * n) {
    *channels = 4;
    out.resize(4 * n);
    for (size_t i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c) out[4 * i + c] = toByte(srgbEncode(fb.rgba[4 * i + c]));
      out[4 * i + 3] = toByte(fb.rgba[4 * i + 3]);
    }
    return out;
  }
  *channels = 3;
  out.assign(3 * n, 0);
  if (fb.has(kAovDepth) && fb.depth.size() == n) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (float z : fb.depth)
      if (std::isfinite(z)) lo = std::min(lo, z), hi = std::max(hi, z);
    for (size_t i = 0; i < n; ++i) {
      const float z = fb.depth[i];
      if (!std::isfinite(z)) continue;
      // Near is bright, far dark, as a display value (not sRGB-encoded); constant depth is white.
      const double t = hi > lo ? (double(hi) - z) / (double(hi) - lo) : 1.0;
      const uint8_t g = toByte(t);
      out[3 * i] = out[3 * i + 1] = out[3 * i + 2] = g;
    }
    return out;
  }
  if (fb.has(kAovNormal) && fb.normal.size() == 3 * n) {
    for (size_t i = 0; i < 3 * n; ++i) out[i] = toByte(fb.normal[i] * 0.5 + 0.5);
    return out;
  }
  throw Error(
      cat("cannot write preview '", path, "': the framebuffer has no color, depth or normal AOV"));
}

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

void writePreview(const std::string& path, const Framebuffer& fb) {
  if (fb.width <= 0 || fb.height <= 0)
    throw Error(cat("cannot write preview '", path, "': empty framebuffer"));
  int channels = 0;
  const std::vector<uint8_t> pixels = previewPixels(fb, path, &channels);
  writeAtomically(
      path,
      [&](const std::string& tmp) {
        auto out = OIIO::ImageOutput::create(tmp);
        if (!out) throw Error(cat("no image writer for this extension: ", OIIO::geterror()));
        OIIO::ImageSpec spec(fb.width, fb.height, channels, OIIO::TypeDesc::UINT8);
        spec.attribute("oiio:ColorSpace", "sRGB");
        if (channels == 4) {
          // The bytes go into the file as computed: no alpha (dis)association by OpenImageIO.
          spec.alpha_channel = 3;
          spec.attribute("oiio:UnassociatedAlpha", 1);
        }
        if (!out->open(tmp, spec)) throw Error(out->geterror());
        if (!out->write_image(OIIO::TypeDesc::UINT8, pixels.data())) {
          const std::string message = out->geterror();
          out->close();
          throw Error(message);
        }
        if (!out->close()) throw Error(out->geterror());
      },
      extensionOf(path));
}

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

  OIIO::ImageSpec spec(test.width, test.height, color ? 4 : 1, OIIO::TypeDesc::FLOAT);
  // The color AOVs are wrapped in place (compare only reads); depth is copied so that misses
  // (+inf in both) compare equal instead of giving inf − inf = NaN.
  std::vector<float> a, b;
  float* pa = const_cast<float*>(test.rgba.data());
  float* pb = const_cast<float*>(reference.rgba.data());
  if (!color) {
    a = test.depth;
    b = reference.depth;
    for (size_t i = 0; i < n; ++i)
      if (std::isinf(a[i]) && a[i] == b[i]) a[i] = b[i] = 0.0f;
    pa = a.data();
    pb = b.data();
  }
  const OIIO::ImageBuf bufA(spec, pa);
  const OIIO::ImageBuf bufB(spec, pb);
  // Thresholds at the float maximum: only the statistics are wanted, and OpenImageIO reports
  // values beyond the failure threshold through the error flag.
  const float never = std::numeric_limits<float>::max();
  const auto result = OIIO::ImageBufAlgo::compare(bufA, bufB, never, never);
  if (result.error) throw Error(cat("image comparison failed: ", OIIO::geterror()));

  ImageDiff diff;
  diff.rmse = result.rms_error;
  diff.maxError = result.maxerror;
  diff.meanError = result.meanerror;
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
