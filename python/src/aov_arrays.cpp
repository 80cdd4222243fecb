#include "aov_arrays.h"

#include <nanobind/ndarray.h>

#include <string>
#include <utility>

#include "core/aov/aov_table.h"

namespace aperture::python {

namespace nb = nanobind;

ArrayLayout layoutOf(const FramePixels& px, const PixelChannel& c, size_t frames) {
  // Layered hits keep their K axis even for K = 1.
  const bool layered = isLayerAovName(c.name);
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

nb::object channelArray(const FramePixels& px, const PixelChannel& c, size_t frames,
                        nb::handle owner) {
  const ArrayLayout l = layoutOf(px, c, frames);
  const nb::dlpack::dtype dtype = c.isFloat ? nb::dtype<float>() : nb::dtype<uint32_t>();
  return nb::cast(nb::ndarray<nb::numpy>(c.data, l.shape.size(), l.shape.data(), owner,
                                         l.strides.data(), dtype));
}

nb::dict pixelArrays(const FramePixels& px, size_t frames, nb::handle owner) {
  nb::dict out;
  for (const PixelChannel& c : px.channels)
    out[c.name.c_str()] = channelArray(px, c, frames, owner);
  return out;
}

nb::dict frameArrays(std::shared_ptr<Framebuffer> fb, size_t frames) {
  // One capsule shares the framebuffer among the arrays; the last array to go frees it.
  auto* holder = new std::shared_ptr<Framebuffer>(std::move(fb));
  nb::capsule owner(holder,
                    [](void* p) noexcept { delete static_cast<std::shared_ptr<Framebuffer>*>(p); });
  return pixelArrays(framePixelsOf(**holder), frames, owner);
}

}  // namespace aperture::python
