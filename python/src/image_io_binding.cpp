// Image files from Python: read_exr (core/exr/exr.h, every AOV of an EXR the CLI wrote), write
// and read (the dataset formats of core/io/dataset_image.h: .png .pfm .npy .tif), and _write_npy
// (an array of any shape as .npy: core/io/npy.h's header, written atomically).
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include <memory>
#include <optional>
#include <vector>

#include "aov_arrays.h"
#include "bindings.h"
#include "core/aov/aov_table.h"
#include "core/exr/exr.h"
#include "core/io/atomic_file.h"
#include "core/io/dataset_image.h"
#include "core/io/npy.h"
#include "core/util/error.h"
#include "file_errors.h"

namespace aperture::python {

namespace {

using AnyArray = nb::ndarray<nb::c_contig, nb::device::cpu>;

/// The AOV an array most likely holds, for messages and format checks, by its layout: the
/// first row of the AOV table with it (depth, normal, color, primid), else "depth".
std::string aovNameOfLayout(int channels, bool isFloat) {
  for (const AovRow& row : aovTable())
    if (row.channels() == channels && row.isFloat() == isFloat) return row.name;
  return isFloat ? "depth" : "primid";
}

size_t writeArray(const std::string& path, const AnyArray& array, double depthScale,
                  const std::optional<std::string>& aov) {
  const bool isFloat = array.dtype() == nb::dtype<float>();
  if (!isFloat && array.dtype() != nb::dtype<uint32_t>())
    throw Error(cat(path, ": the array must be float32 or uint32"));
  if (array.ndim() != 2 && array.ndim() != 3)
    throw Error(cat(path, ": the array must have shape (H, W) or (H, W, C), not ", array.ndim(),
                    " dimensions"));
  ImageView view;
  view.height = int(array.shape(0));
  view.width = int(array.shape(1));
  view.channels = array.ndim() == 3 ? int(array.shape(2)) : 1;
  if (isFloat)
    view.f32 = static_cast<const float*>(array.data());
  else
    view.u32 = static_cast<const uint32_t*>(array.data());
  const std::optional<DatasetFormat> format = datasetFormatOf(path);
  if (!format)
    throw Error(cat(path, ": unknown dataset image extension (known: ",
                    join(datasetExtensions(), " "), "; EXR holds several AOVs: use the CLI)"));
  DatasetWriteOptions options;
  options.depthScale = depthScale;
  DatasetWriteStats stats;
  const std::string name = aov.value_or(aovNameOfLayout(view.channels, isFloat));
  nb::gil_scoped_release release;
  writingFile(path, [&] { stats = writeDatasetImage(path, *format, view, name, options); });
  return stats.outOfRange;
}

nb::object readArray(const std::string& path) {
  auto image = std::make_shared<DatasetImage>();
  readingFiles({path}, [&] { *image = readDatasetImage(path); });
  std::vector<size_t> shape = {size_t(image->height), size_t(image->width)};
  if (image->channels > 1) shape.push_back(size_t(image->channels));
  const bool isFloat = !image->f32.empty() || image->u32.empty();
  const void* data = isFloat ? static_cast<const void*>(image->f32.data()) : image->u32.data();
  auto* holder = new std::shared_ptr<DatasetImage>(image);
  nb::capsule owner(
      holder, [](void* p) noexcept { delete static_cast<std::shared_ptr<DatasetImage>*>(p); });
  return nb::cast(nb::ndarray<nb::numpy>(const_cast<void*>(data), shape.size(), shape.data(), owner,
                                         nullptr,
                                         isFloat ? nb::dtype<float>() : nb::dtype<uint32_t>()));
}

/// Writes a C-order float32 or uint32 array of any shape to `path` as .npy, atomically.
void writeNpy(const std::string& path, const AnyArray& array) {
  const bool isFloat = array.dtype() == nb::dtype<float>();
  if (!isFloat && array.dtype() != nb::dtype<uint32_t>())
    throw Error(cat(path, ": the array must be float32 or uint32"));
  std::vector<uint64_t> shape;
  for (size_t d = 0; d < array.ndim(); ++d) shape.push_back(uint64_t(array.shape(d)));
  const std::string header = npyHeader(isFloat ? "<f4" : "<u4", shape);
  nb::gil_scoped_release release;
  writingFile(path, [&] {
    writePiecesAtomically(path, {{header.data(), header.size()}, {array.data(), array.nbytes()}});
  });
}

nb::dict readExrArrays(const std::string& path) {
  auto fb = std::make_shared<Framebuffer>();
  readingFiles({path}, [&] { *fb = readExr(path); });
  return frameArrays(std::move(fb), 0);
}

}  // namespace

void bindImageIo(nb::module_& m) {
  m.def("read_exr", &readExrArrays, nb::arg("path"),
        "Every AOV of an EXR written by aperture, by AOV name (as render returns them): "
        "float32 or uint32 arrays (H, W[, C]).");
  m.def("_write", &writeArray, nb::arg("path"), nb::arg("array"), nb::arg("depth_scale"),
        nb::arg("aov").none());
  m.def("_write_npy", &writeNpy, nb::arg("path"), nb::arg("array"),
        "A C-contiguous float32 or uint32 array of any shape written to `path` as .npy, "
        "atomically (no partial file, temporaries named as every atomic write's).");
  m.def("read", &readArray, nb::arg("path"),
        "A .pfm or .npy written by aperture.write (or the CLI) as an array (H, W[, C]).");
}

}  // namespace aperture::python
