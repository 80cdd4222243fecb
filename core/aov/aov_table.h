#pragma once
// The fixed AOVs as one table. A row says everything the framebuffer, the EXR writer and
// reader, the dataset writers, the previews, the Python arrays, bench and the docs need to know
// of an AOV; they iterate over the rows. Adding an AOV is a row here (kAov... bit, storage in
// Framebuffer) plus its computation in the frame loop (core/engine/render.cpp).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/aov/framebuffer.h"

namespace aperture {

enum class AovType { Float32, UInt32 };

/// How a preview (core/io/image.h) paints an AOV. A preview shows the first row of the table
/// that has a rule and was rendered, the rows with AovRow::previewFirst (albedo) before the
/// others, each group in table order.
enum class PreviewRule {
  None,      ///< not previewable
  Color,     ///< RGB over the background by coverage A, sRGB-encoded (4 channels)
  Grey,      ///< NEAR white to FAR black (1 float channel; PreviewOptions::depthRange)
  Normal,    ///< n·0.5 + 0.5 (3 float channels; a zero vector is a miss)
  HashedId,  ///< a colour hashed from the ID (1 uint32 channel; kInvalidId is a miss)
};

/// One AOV.
struct AovRow {
  std::string name;   ///< as --aov, job files and Python spell it ("depth", "shading-normal")
  AovMask bit = 0;    ///< its bit in AovSet::mask (a kAov... value for the fixed rows)
  bool inAll = true;  ///< part of "all"
  AovType type = AovType::Float32;
  std::vector<std::string> exrChannels;  ///< one per channel, in interleaved order ("N.X", ...)
  double miss = 0;  ///< every channel's value where the pixel's centre ray hits nothing
  /// The value readExr gives a channel the file lacks while it has others of the AOV; empty:
  /// the miss value (color: an EXR without A is opaque).
  std::vector<double> absentFill;
  bool halfInExr = false;  ///< written as half with ExrOptions::halfColor (--half)
  PreviewRule preview = PreviewRule::None;
  /// Previews prefer it to the rows without it (albedo before color: asked for, it is what a
  /// look at the frame wants to see).
  bool previewFirst = false;
  std::string meaning;  ///< the docs' "frame" column (Markdown)
  /// Its pixels: a member of Framebuffer for the fixed rows (the frame loop stores into them by
  /// name); both null for a registered row, whose pixels are in Framebuffer::registered.
  std::vector<float> Framebuffer::*f32 = nullptr;
  std::vector<uint32_t> Framebuffer::*u32 = nullptr;
  /// Its layered hits (--layers K, core/engine/layers.h), for the 1-channel rows the layer
  /// tracer fills: Framebuffer::layerDepth, ... (layer-major), the AOV "layers.NAME" and the
  /// EXR channels "hit<k>.CHANNEL". Null for the rows without layers.
  std::vector<float> Framebuffer::*layerF32 = nullptr;
  std::vector<uint32_t> Framebuffer::*layerU32 = nullptr;

  int channels() const { return int(exrChannels.size()); }
  bool layered() const { return layerF32 || layerU32; }
  bool isFloat() const { return type == AovType::Float32; }
  /// readExr's value for channel c when the file lacks it.
  double fillOfAbsent(int c) const { return absentFill.empty() ? miss : absentFill[size_t(c)]; }
};

/// Every AOV in the order of aovListString, aovNames, the EXR writer and the docs: the fixed
/// rows, then any registered ones.
const std::vector<AovRow>& aovTable();
/// The row named `name`, or nullptr.
const AovRow* findAovRow(const std::string& name);

/// The pixels of `row` in `fb` (AovRow::isFloat says which of the two). A fixed row's vector is
/// empty when `fb` does not hold it; a registered row's is then an empty vector (const) or an
/// Error (non-const).
std::vector<float>& floatPixels(Framebuffer& fb, const AovRow& row);
std::vector<uint32_t>& uintPixels(Framebuffer& fb, const AovRow& row);
const std::vector<float>& floatPixels(const Framebuffer& fb, const AovRow& row);
const std::vector<uint32_t>& uintPixels(const Framebuffer& fb, const AovRow& row);
/// The number of values `fb` holds for `row` (0 when it does not hold it).
size_t valueCount(const Framebuffer& fb, const AovRow& row);

/// The layered hits of `row` in `fb` (K·W·H values, layer-major; empty without layers), by the
/// row's type. The row must be layered().
const std::vector<float>& layerFloatPixels(const Framebuffer& fb, const AovRow& row);
const std::vector<uint32_t>& layerUintPixels(const Framebuffer& fb, const AovRow& row);
/// "layers.depth": the AOV name of a layered row's hits (aovView, the Python arrays).
std::string layerAovName(const AovRow& row);
/// Whether `aovName` names a row's layered hits ("layers.depth"), as layerAovName spells them.
bool isLayerAovName(const std::string& aovName);
/// "hit2.Z": the EXR channel of layer k of a layered row.
std::string layerChannelName(int layer, const AovRow& row);

/// Adds a row to the table for as long as the object lives (tests, and AOVs computed outside
/// the frame loop): its bit is the lowest one no row uses, its pixels live in
/// Framebuffer::registered. Not thread-safe: register before any framebuffer, parse or file
/// uses the row, and let it go after the last. Throws Error when the name or a channel name is
/// taken, or no bit is left.
class AovRegistration {
 public:
  explicit AovRegistration(AovRow row);
  ~AovRegistration();
  AovRegistration(const AovRegistration&) = delete;
  AovRegistration& operator=(const AovRegistration&) = delete;
  AovMask bit() const { return bit_; }

 private:
  AovMask bit_ = 0;
};

/// "color, depth, distance, normal, position, primid, geomid, all, shading-normal": the rows in
/// "all", then "all", then the rest, as help texts list the names --aov takes.
std::string aovNameList();

/// The channels of every row as the reader's "no aperture channels" message lists them:
/// "R G B A, Z, T, N.*, P.*, primID, geomID, Ns.*".
std::string exrChannelSummary();

/// The names of the rows a dataset layout holds (`holds(channels, isFloat)`), comma-separated.
std::string aovNamesWhere(const std::function<bool(int channels, bool isFloat)>& holds);

/// The Markdown table of every AOV (the fixed rows and the mesh properties face.NAME,
/// vertex.NAME), as docs/aovs.md and the README hold it; a test keeps them equal.
std::string aovMarkdownTable();

}  // namespace aperture
