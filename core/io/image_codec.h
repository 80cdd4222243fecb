#pragma once
// Image files through OpenImageIO (PNG and JPEG previews, 16-bit PNG depth, TIFF, the sizes of
// NeRF frames, image comparison), behind a small interface whose one implementation,
// core/io/oiio_codec.cpp, is a plugin: libaperture_oiio.so, loaded on first use. Debian's
// OpenImageIO brings 261 shared libraries (DICOM, HEIF, OpenCV, FFmpeg, ...); linked into the
// program they cost every process 0.22 s and 130 MB before main(), so `aperture --version`, a
// render to EXR and `import aperture` would pay for codecs they never call.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace aperture {

/// The sample types the codec writes and converts to.
enum class SampleType { UInt8, UInt16, UInt32, Float };

/// An image to encode: width x height pixels of `channels` interleaved samples of `type`, the
/// file's string attributes by OpenImageIO name ("ImageDescription", "oiio:ColorSpace",
/// "compression"), and the writer's integer settings ("png:compressionLevel", "png:filter"),
/// which say how to encode and are not stored (OpenImageIO's PNG writer stores a string one as
/// a tEXt chunk).
struct ImageToEncode {
  int width = 0, height = 0, channels = 0;
  SampleType type = SampleType::UInt8;
  const void* pixels = nullptr;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::vector<std::pair<std::string, int>> settings;
};

/// What an image file is: size, channels, sample type, format and description.
struct ImageFileInfo {
  int width = 0, height = 0, channels = 0;
  std::optional<SampleType> type;  ///< the file's sample type, when it is one of SampleType
  std::string format;              ///< OpenImageIO's name of the file format: "png", "tiff", ...
  std::string description;         ///< the ImageDescription attribute ("" when none)
};

/// Per-sample statistics of a − b (OpenImageIO's ImageBufAlgo::compare).
struct SampleDifference {
  double rms = 0, max = 0, mean = 0;
};

/// How a texture repeats outside [0, 1] (OpenImageIO's periodic, clamp and mirror wraps).
enum class TextureWrapMode { Periodic, Clamp, Mirror };

/// A texture to open for sampling: a file, or an encoded image in memory.
struct TextureToOpen {
  std::string path;                      ///< the file; empty for an image in memory
  const unsigned char* bytes = nullptr;  ///< the encoded image in memory (PNG, JPEG, ...)
  size_t size = 0;
  std::string extension;  ///< the in-memory image's format as an extension (".png"), a hint
  TextureWrapMode wrapS = TextureWrapMode::Periodic, wrapT = TextureWrapMode::Periodic;
  bool nearest = false;  ///< closest texel; else bilinear
  bool srgb = true;      ///< colour samples sRGB-encoded: decoded to linear before filtering
};

/// Opened textures. `sample` is safe from any number of threads at once.
class TextureSet {
 public:
  virtual ~TextureSet() = default;
  /// Linear RGBA of texture `texture` at (s, t), (0, 0) the image's top-left corner; nothing
  /// but (0, 0, 0, 0) for an index out of range.
  virtual void sample(int texture, float s, float t, float rgba[4]) const = 0;
};

/// What aperture asks of OpenImageIO. Every call reports failure by returning false with
/// `error` set (no exception crosses the plugin boundary).
class ImageCodec {
 public:
  virtual ~ImageCodec() = default;
  /// The bytes a file at `path` would hold, its format chosen by the extension, encoded in
  /// memory (the caller writes them with writeBytesAtomically: OpenImageIO's PNG writer does
  /// not report a full disk, and libjpeg exits the process on one).
  virtual bool encode(const std::string& path, const ImageToEncode& image,
                      std::vector<unsigned char>& bytes, std::string& error) const = 0;
  /// Opens the image file `path`: its size, channels and sample type, and when `pixels` is
  /// given, all of its pixels, interleaved, converted to samples of `as` (OpenImageIO's
  /// conversion) and held as bytes. `info` is filled once the file opens, even when decoding
  /// its pixels then fails (and stays as it was when the file does not open).
  virtual bool read(const std::string& path, SampleType as, ImageFileInfo& info,
                    std::vector<unsigned char>* pixels, std::string& error) const = 0;
  /// Compares two float images of width x height pixels of `channels` samples.
  virtual bool compare(int width, int height, int channels, const float* a, const float* b,
                       SampleDifference& difference, std::string& error) const = 0;
  /// Decodes `textures` (all of them, now) for sampling through OpenImageIO's TextureSystem.
  /// On failure, `failed` is the index of the texture that did not open.
  virtual bool openTextures(const std::vector<TextureToOpen>& textures,
                            std::unique_ptr<TextureSet>& opened, size_t& failed,
                            std::string& error) const = 0;
};

/// The plugin's entry point, extern "C" in libaperture_oiio.so (declared below the
/// namespace); the version in its name changes with any change to ImageCodec.
#define APERTURE_IMAGE_CODEC_ENTRY aperture_image_codec_v3
#define APERTURE_IMAGE_CODEC_NAME_OF(entry) #entry
#define APERTURE_IMAGE_CODEC_NAME(entry) APERTURE_IMAGE_CODEC_NAME_OF(entry)
inline constexpr const char* kImageCodecEntry =
    APERTURE_IMAGE_CODEC_NAME(APERTURE_IMAGE_CODEC_ENTRY);

/// The codec: the one the program links in (aperture_oiio_linked, in the test and fuzz
/// programs of sanitizer and fuzz builds), else, loaded at the first call, libaperture_oiio.so
/// from the folder of the program or Python module that holds aperture, else from the build
/// tree it was built in, or only the file $APERTURE_IMAGE_CODEC names when it is set. Throws
/// Error, naming the paths tried, when none loads.
const ImageCodec& imageCodec();

/// imageCodec().encode, throwing Error with the codec's message when it fails.
std::vector<unsigned char> encodeImage(const std::string& path, const ImageToEncode& image);

}  // namespace aperture

extern "C" const aperture::ImageCodec* APERTURE_IMAGE_CODEC_ENTRY();
