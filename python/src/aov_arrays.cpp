#include "aov_arrays.h"

#include <nanobind/ndarray.h>

#include <cstring>
#include <string>

namespace aperture::python {

namespace nb = nanobind;

namespace {

/// How many layers a view holds, layer-major (layered hits, ImageView::layers, which comes
/// with the layered-hits change; 1 for views without the field). Read through overloads so
/// this file needs no change when the field arrives.
template <class View>
auto layersOf(const View& v, int) -> decltype(int(v.layers)) {
  return v.layers;
}
template <class View>
int layersOf(const View&, long) {
  return 1;
}

/// The shape of an AOV: leading dimensions, then K when the view holds K > 1 layers, then
/// H, W, and C when C > 1.
std::vector<size_t> shapeOf(std::vector<size_t> lead, const ImageView& v) {
  if (layersOf(v, 0) > 1) lead.push_back(size_t(layersOf(v, 0)));
  lead.push_back(size_t(v.height));
  lead.push_back(size_t(v.width));
  if (v.channels > 1) lead.push_back(size_t(v.channels));
  return lead;
}

nb::object arrayOf(const void* data, const std::vector<size_t>& shape, bool isFloat,
                   nb::handle owner) {
  const nb::dlpack::dtype dtype = isFloat ? nb::dtype<float>() : nb::dtype<uint32_t>();
  return nb::cast(nb::ndarray<nb::numpy>(const_cast<void*>(data), shape.size(), shape.data(), owner,
                                         nullptr, dtype));
}

}  // namespace

nb::dict frameArrays(std::shared_ptr<Framebuffer> fb, bool frameAxis) {
  // One capsule shares the framebuffer among the arrays; the last array to go frees it.
  auto* holder = new std::shared_ptr<Framebuffer>(std::move(fb));
  nb::capsule owner(holder,
                    [](void* p) noexcept { delete static_cast<std::shared_ptr<Framebuffer>*>(p); });
  const Framebuffer& frame = **holder;
  nb::dict out;
  for (const std::string& name : aovNames(frame)) {
    const ImageView v = aovView(frame, name);
    out[name.c_str()] =
        arrayOf(v.f32 ? static_cast<const void*>(v.f32) : v.u32,
                shapeOf(frameAxis ? std::vector<size_t>{1} : std::vector<size_t>{}, v),
                v.f32 != nullptr, owner);
  }
  return out;
}

nb::dict stackedArrays(std::vector<Framebuffer>& frames) {
  nb::dict out;
  if (frames.empty()) return out;
  const std::vector<std::string> names = aovNames(frames[0]);
  // One block per AOV, owned by its own capsule.
  std::vector<char*> blocks;
  std::vector<size_t> frameBytes;
  for (const std::string& name : names) {
    const ImageView v = aovView(frames[0], name);
    const size_t bytes =
        size_t(layersOf(v, 0)) * size_t(v.width) * size_t(v.height) * size_t(v.channels) * 4;
    char* block = new char[bytes * frames.size()];
    nb::capsule owner(block, [](void* p) noexcept { delete[] static_cast<char*>(p); });
    out[name.c_str()] = arrayOf(block, shapeOf({frames.size()}, v), v.f32 != nullptr, owner);
    blocks.push_back(block);
    frameBytes.push_back(bytes);
  }
  for (size_t k = 0; k < frames.size(); ++k) {
    for (size_t a = 0; a < names.size(); ++a) {
      const ImageView v = aovView(frames[k], names[a]);
      std::memcpy(blocks[a] + k * frameBytes[a], v.f32 ? static_cast<const void*>(v.f32) : v.u32,
                  frameBytes[a]);
    }
    frames[k] = Framebuffer();
  }
  return out;
}

}  // namespace aperture::python
