// The ImageCodec of core/io/image_codec.h over OpenImageIO: built as the plugin
// libaperture_oiio.so, the only part of aperture that links OpenImageIO.
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <limits>

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
