// The ImageCodec of core/io/image_codec.h over OpenImageIO: built as the plugin
// libaperture_oiio.so, the only part of aperture that links OpenImageIO.
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imagecache.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>

#include "core/io/image_codec.h"

namespace aperture {
namespace {

OIIO::TypeDesc typeDescOf(SampleType type) {
  switch (type) {
    case SampleType::UInt8:
      return OIIO::TypeDesc::UINT8;
    case SampleType::UInt16:
      return OIIO::TypeDesc::UINT16;
    case SampleType::UInt32:
      return OIIO::TypeDesc::UINT32;
    case SampleType::Float:
      return OIIO::TypeDesc::FLOAT;
  }
  return OIIO::TypeDesc::UNKNOWN;
}

std::optional<SampleType> sampleTypeOf(OIIO::TypeDesc type) {
  for (SampleType t :
       {SampleType::UInt8, SampleType::UInt16, SampleType::UInt32, SampleType::Float})
    if (type == typeDescOf(t)) return t;
  return std::nullopt;
}

/// A texture decoded to linear RGBA floats, top row first.
struct DecodedTexture {
  int width = 0, height = 0;
  std::vector<float> rgba;
};

/// The decoded textures of every open TextureSet by the name its ImageCache knows them by:
/// MemoryInput (below) serves them, as the ImageCache's creator of an image takes no argument
/// but the name.
std::mutex memoryTexturesMutex;
std::map<std::string, std::shared_ptr<const DecodedTexture>> memoryTextures;

std::shared_ptr<const DecodedTexture> memoryTexture(const std::string& name) {
  const std::lock_guard<std::mutex> lock(memoryTexturesMutex);
  const auto it = memoryTextures.find(name);
  return it == memoryTextures.end() ? nullptr : it->second;
}

/// An ImageInput over a decoded texture in memory: one untiled float RGBA image, no mipmaps.
class MemoryInput final : public OIIO::ImageInput {
 public:
  const char* format_name() const override { return "aperture-memory"; }
  bool open(const std::string& name, OIIO::ImageSpec& newspec) override {
    texture_ = memoryTexture(name);
    if (!texture_) {
      errorfmt("no decoded texture named {}", name);
      return false;
    }
    m_spec = OIIO::ImageSpec(texture_->width, texture_->height, 4, OIIO::TypeDesc::FLOAT);
    m_spec.attribute("oiio:UnassociatedAlpha", 1);
    newspec = m_spec;
    return true;
  }
  bool close() override {
    texture_.reset();
    return true;
  }
  bool read_native_scanline(int subimage, int miplevel, int y, int /*z*/, void* data) override {
    if (!texture_ || subimage != 0 || miplevel != 0 || y < 0 || y >= texture_->height) return false;
    const size_t row = 4 * size_t(texture_->width);
    std::copy_n(texture_->rgba.data() + row * size_t(y), row, static_cast<float*>(data));
    return true;
  }
  static OIIO::ImageInput* create() { return new MemoryInput; }

 private:
  std::shared_ptr<const DecodedTexture> texture_;
};

/// sRGB-encoded c in [0, 1] as linear (IEC 61966-2-1).
float srgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

/// The texture decoded to linear RGBA: gray to RGB, alpha 1 when it has none; sRGB colour
/// samples decoded (alpha never is). Returns false with `error` set when it does not decode.
bool decodeTexture(const TextureToOpen& texture, DecodedTexture& out, std::string& error) {
  // Straight alpha, as glTF and MTL images mean it: OpenImageIO's PNG reader would otherwise
  // premultiply the colours.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  OIIO::Filesystem::IOMemReader memory(texture.bytes, texture.size);
  OIIO::Filesystem::IOProxy* proxy = &memory;
  const bool inMemory = texture.path.empty();
  if (inMemory) config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto in = inMemory ? OIIO::ImageInput::open("embedded" + texture.extension, &config, &memory)
                     : OIIO::ImageInput::open(texture.path, &config);
  if (!in) {
    error = OIIO::geterror();
    return false;
  }
  const OIIO::ImageSpec& spec = in->spec();
  const int channels = spec.nchannels;
  if (spec.width <= 0 || spec.height <= 0 || channels <= 0 || spec.depth > 1) {
    error = "not a 2D image";
    return false;
  }
  std::vector<float> pixels(spec.image_pixels() * size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, pixels.data())) {
    error = in->geterror();
    return false;
  }
  in->close();
  out.width = spec.width, out.height = spec.height;
  out.rgba.resize(4 * spec.image_pixels());
  const bool gray = channels < 3;
  const int alpha = channels == 2 ? 1 : channels >= 4 ? 3 : -1;
  for (size_t i = 0; i < spec.image_pixels(); ++i) {
    const float* p = &pixels[i * size_t(channels)];
    float* q = &out.rgba[4 * i];
    for (int c = 0; c < 3; ++c) {
      const float value = p[gray ? 0 : c];
      q[c] = texture.srgb ? srgbToLinear(value) : value;
    }
    q[3] = alpha >= 0 ? p[alpha] : 1.0f;
  }
  return true;
}

OIIO::TextureOpt::Wrap wrapOf(TextureWrapMode mode) {
  switch (mode) {
    case TextureWrapMode::Periodic:
      return OIIO::TextureOpt::WrapPeriodic;
    case TextureWrapMode::Clamp:
      return OIIO::TextureOpt::WrapClamp;
    case TextureWrapMode::Mirror:
      return OIIO::TextureOpt::WrapMirror;
  }
  return OIIO::TextureOpt::WrapPeriodic;
}

/// Textures in OpenImageIO's shared TextureSystem, each an image in memory (MemoryInput) under
/// a name of this set's own, sampled at its finest level with zero-width footprints. Not a
/// private TextureSystem: OpenImageIO 2.4's TextureSystem::destroy frees a private one with a
/// delete of another size than its create allocated (AddressSanitizer's
/// new-delete-type-mismatch, inside libOpenImageIO); the shared one lives as long as the
/// process, and a set drops its files from it when it goes.
class OiioTextureSet final : public TextureSet {
 public:
  OiioTextureSet() : system_(OIIO::TextureSystem::create(/*shared=*/true)) {
    static std::atomic<uint64_t> sets{0};
    prefix_ = "aperture-texture-" + std::to_string(sets++) + "-";
  }
  ~OiioTextureSet() override {
    for (const Entry& e : entries_) system_->invalidate(e.name, /*force=*/true);
    const std::lock_guard<std::mutex> lock(memoryTexturesMutex);
    for (const Entry& e : entries_) memoryTextures.erase(e.name.string());
  }
  OiioTextureSet(const OiioTextureSet&) = delete;
  OiioTextureSet& operator=(const OiioTextureSet&) = delete;

  /// Adds the decoded texture as the next index; false with `error` set when OpenImageIO does
  /// not take it.
  bool add(const TextureToOpen& texture, std::shared_ptr<const DecodedTexture> decoded,
           std::string& error) {
    Entry e;
    e.name = OIIO::ustring(prefix_ + std::to_string(entries_.size()));
    {
      const std::lock_guard<std::mutex> lock(memoryTexturesMutex);
      memoryTextures[e.name.string()] = std::move(decoded);
    }
    entries_.push_back(e);
    if (!system_->imagecache()->add_file(e.name, &MemoryInput::create)) {
      error = system_->geterror();
      return false;
    }
    entries_.back().handle = system_->get_texture_handle(e.name);
    if (!entries_.back().handle || !system_->good(entries_.back().handle)) {
      error = system_->geterror();
      return false;
    }
    entries_.back().swrap = wrapOf(texture.wrapS), entries_.back().twrap = wrapOf(texture.wrapT);
    entries_.back().interp =
        texture.nearest ? OIIO::TextureOpt::InterpClosest : OIIO::TextureOpt::InterpBilinear;
    return true;
  }

  void sample(int texture, float s, float t, float rgba[4]) const override {
    std::fill_n(rgba, 4, 0.0f);
    if (texture < 0 || size_t(texture) >= entries_.size()) return;
    const Entry& e = entries_[size_t(texture)];
    OIIO::TextureOpt opt;
    opt.swrap = e.swrap, opt.twrap = e.twrap;
    opt.interpmode = e.interp;
    opt.mipmode = OIIO::TextureOpt::MipModeNoMIP;  // the finest level: zero-width footprints
    opt.fill = 0.0f;
    system_->texture(e.handle, system_->get_perthread_info(), opt, s, t, 0, 0, 0, 0, 4, rgba);
  }

 private:
  struct Entry {
    OIIO::ustring name;
    OIIO::TextureSystem::TextureHandle* handle = nullptr;
    OIIO::TextureOpt::Wrap swrap = OIIO::TextureOpt::WrapPeriodic,
                           twrap = OIIO::TextureOpt::WrapPeriodic;
    OIIO::TextureOpt::InterpMode interp = OIIO::TextureOpt::InterpBilinear;
  };
  OIIO::TextureSystem* system_;
  std::string prefix_;
  std::vector<Entry> entries_;
};

class OiioCodec final : public ImageCodec {
 public:
  bool encode(const std::string& path, const ImageToEncode& image,
              std::vector<unsigned char>& bytes, std::string& error) const override {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) return fail(error, "no image writer for this extension: " + OIIO::geterror());
    if (!out->supports("ioproxy"))
      return fail(error,
                  std::string("the ") + out->format_name() + " writer cannot encode to memory");
    OIIO::Filesystem::IOVecOutput memory(bytes);
    OIIO::Filesystem::IOProxy* proxy = &memory;
    const OIIO::TypeDesc type = typeDescOf(image.type);
    OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
    for (const auto& [name, value] : image.attributes) spec.attribute(name, value);
    for (const auto& [name, value] : image.settings) spec.attribute(name, value);
    spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    // libtiff fails to write the Exif directory into memory and, with a colour space set, the
    // file is left without its ImageLength tag; aperture's images need no Exif data.
    spec.attribute("tiff:write_exif", 0);
    if (!out->open(path, spec)) return fail(error, out->geterror());
    if (!out->write_image(type, image.pixels)) {
      error = out->geterror();
      out->close();
      return false;
    }
    if (!out->close()) return fail(error, out->geterror());
    return true;
  }

  bool read(const std::string& path, SampleType as, ImageFileInfo& info,
            std::vector<unsigned char>* pixels, std::string& error) const override {
    auto in = OIIO::ImageInput::open(path);
    if (!in) return fail(error, OIIO::geterror());
    const OIIO::ImageSpec spec = in->spec();
    info = {spec.width,        spec.height,
            spec.nchannels,    sampleTypeOf(spec.format),
            in->format_name(), spec.get_string_attribute("ImageDescription")};
    if (pixels) {
      const OIIO::TypeDesc type = typeDescOf(as);
      pixels->resize(spec.image_pixels() * size_t(spec.nchannels) * type.size());
      if (!in->read_image(0, 0, 0, spec.nchannels, type, pixels->data()))
        return fail(error, in->geterror());
    }
    in->close();
    return true;
  }

  bool openTextures(const std::vector<TextureToOpen>& textures, std::unique_ptr<TextureSet>& opened,
                    size_t& failed, std::string& error) const override {
    auto set = std::make_unique<OiioTextureSet>();
    for (size_t k = 0; k < textures.size(); ++k) {
      auto decoded = std::make_shared<DecodedTexture>();
      failed = k;
      if (!decodeTexture(textures[k], *decoded, error)) return false;
      if (!set->add(textures[k], std::move(decoded), error)) return false;
    }
    opened = std::move(set);
    return true;
  }

  bool compare(int width, int height, int channels, const float* a, const float* b,
               SampleDifference& difference, std::string& error) const override {
    const OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
    // compare only reads the wrapped buffers.
    const OIIO::ImageBuf bufA(spec, const_cast<float*>(a));
    const OIIO::ImageBuf bufB(spec, const_cast<float*>(b));
    // Thresholds at the float maximum: only the statistics are wanted, and OpenImageIO
    // reports values beyond the failure threshold through the error flag.
    const float never = std::numeric_limits<float>::max();
    const auto result = OIIO::ImageBufAlgo::compare(bufA, bufB, never, never);
    if (result.error) return fail(error, OIIO::geterror());
    difference = {result.rms_error, result.maxerror, result.meanerror};
    return true;
  }

 private:
  static bool fail(std::string& error, const std::string& message) {
    error = message;
    return false;
  }
};

}  // namespace
}  // namespace aperture

extern "C" __attribute__((visibility("default"))) const aperture::ImageCodec*
APERTURE_IMAGE_CODEC_ENTRY() {
  static const aperture::OiioCodec codec;
  return &codec;
}
