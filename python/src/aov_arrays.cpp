#include "aov_arrays.h"

#include <nanobind/ndarray.h>

#include <cstdint>
#include <string>
#include <vector>

namespace aperture::python {

namespace nb = nanobind;

namespace {

/// Shape and strides (in elements) of one AOV's array; see frameArrays.
struct ArrayLayout {
  std::vector<size_t> shape;
  std::vector<int64_t> strides;
  void add(size_t extent, size_t stride) {
    shape.push_back(extent);
    strides.push_back(int64_t(stride));
  }
};

/// `layered`: a layered-hits AOV ("layers.*"), which keeps its K axis even for K = 1.
ArrayLayout layoutOf(const ImageView& v, size_t frames, bool layered) {
  const size_t n = frames == 0 ? 1 : frames;
  const size_t h = size_t(v.height) / n, w = size_t(v.width), c = size_t(v.channels);
  const size_t frameValues = h * w * c;
  ArrayLayout l;
  if (frames > 0) l.add(n, frameValues);
  if (layered) l.add(size_t(v.layers), n * frameValues);  // layer-major storage
  l.add(h, w * c);
  l.add(w, c);
  if (c > 1) l.add(c, 1);
  return l;
}

nb::object arrayOf(const ImageView& v, const ArrayLayout& l, nb::handle owner) {
  const void* data = v.f32 ? static_cast<const void*>(v.f32) : static_cast<const void*>(v.u32);
  const nb::dlpack::dtype dtype = v.f32 ? nb::dtype<float>() : nb::dtype<uint32_t>();
  return nb::cast(nb::ndarray<nb::numpy>(const_cast<void*>(data), l.shape.size(), l.shape.data(),
                                         owner, l.strides.data(), dtype));
}

}  // namespace

nb::dict frameArrays(std::shared_ptr<Framebuffer> fb, size_t frames) {
  // One capsule shares the framebuffer among the arrays; the last array to go frees it.
  auto* holder = new std::shared_ptr<Framebuffer>(std::move(fb));
  nb::capsule owner(holder,
                    [](void* p) noexcept { delete static_cast<std::shared_ptr<Framebuffer>*>(p); });
  const Framebuffer& frame = **holder;
  nb::dict out;
  for (const std::string& name : aovNames(frame)) {
    const ImageView v = aovView(frame, name);
    out[name.c_str()] = arrayOf(v, layoutOf(v, frames, name.rfind("layers.", 0) == 0), owner);
  }
  return out;
}

}  // namespace aperture::python
