#pragma once
// Previews and image comparison through OpenImageIO (the image codec, core/io/image_codec.h).
#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/aov/framebuffer.h"

namespace aperture {

/// How a preview maps its AOV to 8-bit display values.
struct PreviewOptions {
  /// NEAR, FAR in scene units (0 <= NEAR < FAR, both finite): a depth preview maps NEAR to
  /// white (255) and FAR to black (0), linearly, clamped outside. Absent: each image uses its
  /// own nearest and farthest finite depth. Ignored by previews of other AOVs.
  std::optional<glm::dvec2> depthRange;
};

/// The colour of pixels that hit nothing in every preview (and what color previews are
/// composited over): a dark slate blue, as sRGB bytes. No ID colour and no grey equals it.
inline constexpr std::array<uint8_t, 3> kPreviewBackground = {38, 50, 72};

/// The AOVs a preview can show: the rows of the AOV table with a PreviewRule
/// (core/aov/aov_table.h), in order of preference: albedo, color, depth, normal, primid,
/// geomid, instance, mesh, material (previewableAovText).
AovMask previewableAovMask();

/// The requested AOVs a preview could show (`aovs & previewableAovMask()`); 0 means a preview
/// of such a framebuffer cannot be written, which callers check before rendering.
inline AovMask previewableAovs(AovMask aovs) { return aovs & previewableAovMask(); }

/// The one AOV a preview of a framebuffer with `aovs` shows: the first previewable AOV in order
/// of preference (AovRow::previewFirst rows, then the others, in table order), or 0 when there
/// is none.
Aov previewAov(AovMask aovs);

/// "color, else depth, normal, primid or geomid": the previewable AOVs in order, for help texts.
std::string previewableAovText();

/// A format a preview is written in (by OpenImageIO), picked by the path's extension.
struct PreviewFormat {
  const char* name;                     ///< "PNG", "JPEG", ...
  std::vector<std::string> extensions;  ///< lower case, with the dot
};
/// The preview formats: PNG, JPEG, TIFF, BMP, Targa, PPM. The one list the output checks
/// (apps/outputs.h), writePreview, the help texts and the README's list come from.
const std::vector<PreviewFormat>& previewFormats();
/// Every extension of previewFormats(), in order: .png .jpg .jpeg .tif .tiff .bmp .tga .ppm.
const std::vector<std::string>& previewExtensions();

/// Writes an opaque 8-bit RGB preview of `fb` to `path` (the format of previewFormats() its
/// extension names), atomically. Throws Error naming `path`. It shows
/// previewAov(fb.aovs):
///  - color: R G B composited over kPreviewBackground by coverage A (the color AOV is
///    premultiplied: c + (1 − A)·background, in linear light), clamped, sRGB-encoded;
///  - depth: grey, NEAR white to FAR black (options.depthRange, else the image's own range;
///    a constant depth is white), not sRGB-encoded; misses are the background;
///  - normal: n·0.5 + 0.5 per channel; misses (zero normal) are the background;
///  - primID / geomID: a colour hashed from the ID (hash32 of core/util/sampling.h), every
///    channel in [96, 255]; equal IDs give equal colours; misses are the background.
/// The file's ImageDescription says which AOV it shows and, for depth, the range used.
void writePreview(const std::string& path, const Framebuffer& fb,
                  const PreviewOptions& options = {});

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
