#include "named_arrays.h"

#include <nanobind/ndarray.h>

#include <cstdint>

#include "core/util/error.h"

namespace aperture::python {

namespace nb = nanobind;

namespace {

nb::dlpack::dtype dtypeOf(const NpzArray& a) {
  if (a.descr == "|u1") return nb::dtype<uint8_t>();
  if (a.descr == "<u2") return nb::dtype<uint16_t>();
  if (a.descr == "<u4") return nb::dtype<uint32_t>();
  if (a.descr == "<u8") return nb::dtype<uint64_t>();
  if (a.descr == "<i4") return nb::dtype<int32_t>();
  if (a.descr == "<f4") return nb::dtype<float>();
  if (a.descr == "<f8") return nb::dtype<double>();
  throw Error(cat("array '", a.name, "': dtype ", a.descr, " has no NumPy conversion here"));
}

}  // namespace

nb::dict namedArrays(std::shared_ptr<const void> owner, const std::vector<NpzArray>& arrays) {
  auto* holder = new std::shared_ptr<const void>(std::move(owner));
  nb::capsule capsule(
      holder, [](void* p) noexcept { delete static_cast<std::shared_ptr<const void>*>(p); });
  nb::dict out;
  for (const NpzArray& a : arrays) {
    std::vector<size_t> shape(a.shape.begin(), a.shape.end());
    out[a.name.c_str()] = nb::cast(nb::ndarray<nb::numpy>(
        const_cast<void*>(a.data), shape.size(), shape.data(), capsule, nullptr, dtypeOf(a)));
  }
  return out;
}

}  // namespace aperture::python
