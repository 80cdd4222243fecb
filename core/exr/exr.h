#pragma once
// Multi-channel EXR output and input through OpenEXR.
#include <string>
#include <utility>
#include <vector>

#include "core/aov/framebuffer.h"
#include "core/engine/camera.h"

namespace aperture {

/// EXR compression by name: none rle zips zip piz pxr24 b44 b44a dwaa dwab.
enum class ExrCompression { None, Rle, Zips, Zip, Piz, Pxr24, B44, B44a, Dwaa, Dwab };
ExrCompression parseExrCompression(const std::string& name);  ///< throws Error listing names
std::string exrCompressionName(ExrCompression c);

struct ExrOptions {
  ExrCompression compression = ExrCompression::Zip;
  bool halfColor = false;  ///< R G B A as half; geometry channels are always float32
  /// --deep: the layered hits go to a deep EXR beside this one (core/exr/exr_deep.h) instead of
  /// the flat hit<k>.* channels, which writeExr and exrChannelNames then leave out.
  bool layersInDeepFile = false;
};

/// What the header records beside the pixels.
struct ExrMetadata {
  CameraDescription camera;
  double renderSeconds = 0;
  /// Further string attributes (software version, mesh, settings).
  std::vector<std::pair<std::string, std::string>> strings;
  /// String vector attributes (OpenEXR's stringvector): the names behind the id AOVs,
  /// "aperture.instanceNames" and the like, each name at its id.
  std::vector<std::pair<std::string, std::vector<std::string>>> stringVectors;
};

/// Writes every allocated AOV of `fb` to `path` with the channel names of the README
/// (R G B A, Z, T, N.X.., P.X.., primID, geomID, Ns.X.. float32, and a UINT channel per mesh
/// property named like its AOV, "face.object_id"). The header carries OpenEXR's standard
/// attributes as CameraDescription defines them (pixelAspectRatio, screenWindowCenter/Width,
/// worldToCamera, and worldToNDC unless the camera is a panorama; float, Imath row vectors),
/// double copies "aperture.worldToCamera"/"aperture.worldToNDC", a panorama's projection
/// ("aperture.equirect.*", "aperture.fisheye.*"), the camera (type, eye, U, V, W, d,
/// viewport), spp and render time. Written to a temporary file in the same directory and
/// renamed: a failure leaves no file under `path` and any previous file intact. Throws Error,
/// also for a pixel aspect ratio outside OpenEXR's [1e-6, 1e6].
void writeExr(const std::string& path, const Framebuffer& fb, const ExrMetadata& meta,
              const ExrOptions& options = {});

/// The threads of OpenEXR's global pool, which encodes and decodes the chunks of every file
/// the process writes or reads (0: each file in the thread that writes or reads it).
int exrThreads();

/// While alive, OpenEXR's pool has `threads` threads for writing files with `compression`:
/// with zip, the default, encoding is the slowest part of a batch (a 1080p depth,normal image
/// takes it 0.4 s on one thread), and the pool shares it out (1.5x faster batches on 2
/// cores, bench/RESULTS.md, twelfth session). None for one thread, and none for an
/// uncompressed file: there the pool only hands each scanline to another thread, which made a
/// batch 4 % slower. Restores the count it found. Pixels and file bytes do not depend on it.
class ExrEncodingThreads {
 public:
  ExrEncodingThreads(int threads, ExrCompression compression);
  ~ExrEncodingThreads();
  ExrEncodingThreads(const ExrEncodingThreads&) = delete;
  ExrEncodingThreads& operator=(const ExrEncodingThreads&) = delete;

 private:
  int previous_;
};

/// Reads an EXR written by writeExr back into a Framebuffer (AOVs from the channel names;
/// half channels widened to float; property channels, UINT "face.*" / "vertex.*", in the
/// file's channel order, which OpenEXR sorts by name). With `meta`, the header comes back as
/// written, except that string attributes (camera extras, `strings`) and `stringVectors` come
/// back sorted by name.
/// Throws Error for unreadable or incomplete files.
Framebuffer readExr(const std::string& path, ExrMetadata* meta = nullptr);

/// True if `path` is a complete, readable EXR (every scanline present); used by --resume.
bool isCompleteExr(const std::string& path);

/// The channel names writeExr gives the AOVs of `aovs` (R G B A, Z, T, N.X.., P.X.., primID,
/// geomID, Ns.X.., then the property channels), in the order of the AovMask bits, then the
/// layered hits: layer k (0-based, nearest first) as the OpenEXR layer "hit<k>": hit<k>.Z,
/// hit<k>.T (float, +inf past the last surface), hit<k>.primID, hit<k>.geomID (UINT,
/// 0xFFFFFFFF there); docs/layers.md. No hit<k>.* with `options.layersInDeepFile`.
std::vector<std::string> exrChannelNames(const AovSet& aovs, const ExrOptions& options = {});

/// An EXR's header, read without decoding any pixel.
struct ExrHeader {
  int width = 0, height = 0;          ///< data window size, pixels
  std::vector<std::string> channels;  ///< channel names as stored (OpenEXR sorts them by name)
  ExrMetadata meta;                   ///< as readExr gives it
};

/// Reads the header of `path`. Throws Error naming the file for an unreadable header; says
/// nothing about the pixels (see isCompleteExr).
ExrHeader readExrHeader(const std::string& path);

}  // namespace aperture
