#pragma once
// Previews and image comparison through OpenImageIO.
#include <string>

#include "core/framebuffer.h"

namespace aperture {

/// Writes an 8-bit sRGB preview of the color AOV (or of depth/normal when color was not
/// rendered) to `path` (PNG or any format OpenImageIO writes), atomically. Throws Error.
/// Color: RGB clamped to [0, 1] and sRGB-encoded, alpha kept (linear). Without color: depth
/// as grey, 255 at the nearest finite depth to 0 at the farthest, misses black; else normals
/// as n * 0.5 + 0.5.
void writePreview(const std::string& path, const Framebuffer& fb);

/// Error statistics of `test` against `reference` over a float channel set, computed with
/// OpenImageIO's ImageBufAlgo::compare.
struct ImageDiff {
  double rmse = 0;
  double psnr = 0;  ///< 20 log10(peak / rmse), peak given to compareColor; inf if equal
  double maxError = 0;
  double meanError = 0;
  double primIdMismatch = 0;  ///< share of pixels whose primID differs (if both have it)
  double depthRelError = 0;   ///< mean |Z − Zref| / |Zref| over pixels finite in both, Zref ≠ 0
};
ImageDiff compareFramebuffers(const Framebuffer& test, const Framebuffer& reference,
                              double peak = 1.0);

}  // namespace aperture
