#include "core/io/texture_sampler.h"

#include "core/util/error.h"

namespace aperture {

std::shared_ptr<const TextureSampler> openTextureSampler(
    const std::vector<SurfaceTexture>& textures) {
  if (!textures.empty())
    throw Error(cat(textures.front().where, ": texture sampling is not implemented yet"));
  return nullptr;
}

}  // namespace aperture
