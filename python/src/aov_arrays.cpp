#include "aov_arrays.h"

#include <nanobind/ndarray.h>

#include <string>
#include <utility>

#include "core/util/huge_pages.h"

namespace aperture::python {

namespace nb = nanobind;

namespace {

nb::object arrayOf(const PixelChannel& c, const ArrayLayout& l, nb::handle owner) {
  const nb::dlpack::dtype dtype = c.isFloat ? nb::dtype<float>() : nb::dtype<uint32_t>();
  return nb::cast(nb::ndarray<nb::numpy>(c.data, l.shape.size(), l.shape.data(), owner,
                                         l.strides.data(), dtype));
}

}  // namespace

ArrayLayout layoutOf(const FramePixels& px, const PixelChannel& c, size_t frames) {
  // Layered hits ("layers.*") keep their K axis even for K = 1.
  const bool layered = c.name.rfind("layers.", 0) == 0;
  const size_t n = frames == 0 ? 1 : frames;
  const size_t h = size_t(px.height) / n, w = size_t(px.width), k = size_t(c.channels);
  const size_t frameValues = h * w * k;
  ArrayLayout l;
  if (frames > 0) l.add(n, frameValues);
  if (layered) l.add(size_t(c.layers), n * frameValues);  // layer-major storage
  l.add(h, w * k);
  l.add(w, k);
  if (k > 1) l.add(k, 1);
  return l;
}

nb::dict pixelArrays(const FramePixels& px, size_t frames, nb::handle owner) {
  nb::dict out;
  for (const PixelChannel& c : px.channels)
    out[c.name.c_str()] = arrayOf(c, layoutOf(px, c, frames), owner);
  return out;
}

nb::dict frameArrays(std::shared_ptr<Framebuffer> fb, size_t frames) {
  // One capsule shares the framebuffer among the arrays; the last array to go frees it.
  auto* holder = new std::shared_ptr<Framebuffer>(std::move(fb));
  nb::capsule owner(holder,
                    [](void* p) noexcept { delete static_cast<std::shared_ptr<Framebuffer>*>(p); });
  return pixelArrays(framePixelsOf(**holder), frames, owner);
}

UnwrittenStorage::~UnwrittenStorage() {
  for (const auto& [data, bytes] : blocks_) deallocateLargeBuffer(data, bytes);
}

void* UnwrittenStorage::allocate(size_t bytes) {
  blocks_.reserve(blocks_.size() + 1);
  void* data = allocateLargeBuffer(bytes);
  blocks_.emplace_back(data, bytes);
  return data;
}

nb::capsule ownerOf(std::unique_ptr<UnwrittenStorage> storage) {
  return nb::capsule(storage.release(),
                     [](void* p) noexcept { delete static_cast<UnwrittenStorage*>(p); });
}

}  // namespace aperture::python
