#include "core/io/texture_sampler.h"

#include "core/io/image_codec.h"
#include "core/util/error.h"

namespace aperture {

namespace {

TextureWrapMode wrapModeOf(TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::Repeat:
      return TextureWrapMode::Periodic;
    case TextureWrap::ClampToEdge:
      return TextureWrapMode::Clamp;
    case TextureWrap::MirroredRepeat:
      return TextureWrapMode::Mirror;
  }
  return TextureWrapMode::Periodic;
}

/// ".png" for "image/png": the in-memory image's format as OpenImageIO guesses it from a name
/// (it tries its other readers when that one refuses the bytes).
std::string extensionOfMimeType(const std::string& mimeType) {
  if (mimeType == "image/jpeg") return ".jpg";
  if (mimeType == "image/webp") return ".webp";
  if (mimeType == "image/ktx2") return ".ktx2";
  return ".png";
}

class CodecTextureSampler final : public TextureSampler {
 public:
  explicit CodecTextureSampler(std::unique_ptr<TextureSet> set) : set_(std::move(set)) {}
  glm::vec4 sample(int texture, float s, float t) const override {
    float rgba[4];
    set_->sample(texture, s, t, rgba);
    return {rgba[0], rgba[1], rgba[2], rgba[3]};
  }

 private:
  std::unique_ptr<TextureSet> set_;
};

}  // namespace

std::shared_ptr<const TextureSampler> openTextureSampler(
    const std::vector<SurfaceTexture>& textures) {
  std::vector<TextureToOpen> open;
  for (const SurfaceTexture& texture : textures) {
    TextureToOpen t;
    t.path = texture.path;
    if (t.path.empty()) {
      if (texture.bytes.empty())
        throw Error(cat(texture.where, ": texture has neither a file nor embedded bytes"));
      t.bytes = texture.bytes.data(), t.size = texture.bytes.size();
      t.extension = extensionOfMimeType(texture.mimeType);
    }
    t.wrapS = wrapModeOf(texture.wrapS), t.wrapT = wrapModeOf(texture.wrapT);
    t.nearest = texture.nearest, t.srgb = texture.srgb;
    open.push_back(std::move(t));
  }
  std::unique_ptr<TextureSet> set;
  size_t failed = 0;
  std::string error;
  if (!imageCodec().openTextures(open, set, failed, error)) {
    const SurfaceTexture& bad = textures[failed];
    throw Error(cat(bad.where, ": texture ",
                    bad.path.empty()
                        ? cat("(embedded, ", bad.bytes.size(), " bytes, ",
                              bad.mimeType.empty() ? "no MIME type" : bad.mimeType, ")")
                        : "'" + bad.path + "'",
                    " does not decode: ", error));
  }
  return std::make_shared<CodecTextureSampler>(std::move(set));
}

}  // namespace aperture
