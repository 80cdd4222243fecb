#pragma once
// The textures of a scene's materials, sampled through OpenImageIO's TextureSystem (in the
// image codec plugin, core/io/image_codec.h), for the albedo AOV.
#include <memory>
#include <vector>

#include "core/mesh/scene_file.h"

namespace aperture {

/// A TextureSampler over `textures` (SceneFile::textures; sample's `texture` indexes them).
/// Each texture is decoded once, here: an external one from SurfaceTexture::path, an embedded
/// one from SurfaceTexture::bytes (never written to disk); its sRGB samples are decoded to
/// linear before any filtering, its gray, gray-alpha or RGB channels widened to RGBA (alpha 1).
/// Sampling follows the texture's wrap modes (Repeat, ClampToEdge, MirroredRepeat) and filter
/// (NEAREST: the texel holding (s, t); else bilinear between the four nearest texel centres),
/// always at the finest level (a footprint of zero width: no mipmaps). (s, t) = (0, 0) is the
/// image's top-left corner, (1, 1) its bottom-right. Safe to call from any number of threads.
/// Throws Error naming SurfaceTexture::where and the path (or "embedded") of a texture that is
/// missing or does not decode. An index out of range samples (0, 0, 0, 0).
std::shared_ptr<const TextureSampler> openTextureSampler(
    const std::vector<SurfaceTexture>& textures);

}  // namespace aperture
