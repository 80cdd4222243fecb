// glTF accessors: every component type, normalized integers (glTF 2.0, 3.11), the integer
// attributes of KHR_mesh_quantization, byteStride, sparse accessors and index types.
#include <algorithm>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/mesh/gltf.h"
#include "core/util/error.h"
#include "core/util/huge_pages.h"
#include "core/util/parallel.h"

namespace aperture::gltf {

namespace {

size_t componentBytes(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

int typeComponents(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return 1;
    case TINYGLTF_TYPE_VEC2:
      return 2;
    case TINYGLTF_TYPE_VEC3:
      return 3;
    case TINYGLTF_TYPE_VEC4:
    case TINYGLTF_TYPE_MAT2:
      return 4;
    case TINYGLTF_TYPE_MAT3:
      return 9;
    case TINYGLTF_TYPE_MAT4:
      return 16;
    default:
      return 0;
  }
}

template <class T>
T load(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

/// Component `p`, an integer of 8 or 16 bits, as a float; when `normalized`, by the glTF
/// formulas: c / (2^b − 1) unsigned, max(c / (2^(b−1) − 1), −1) signed.
template <class T>
float smallIntegerComponent(const unsigned char* p, bool normalized) {
  static_assert(sizeof(T) <= 2, "the largest value must be exact in a float");
  const float c = load<T>(p);
  if (!normalized) return c;
  const float scaled = c / float(std::numeric_limits<T>::max());
  return std::is_signed_v<T> ? std::max(scaled, -1.0f) : scaled;
}

/// Component `p` of type `type` as a float: normalized by the glTF formulas when `normalized`.
float component(const unsigned char* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return smallIntegerComponent<int8_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return smallIntegerComponent<uint8_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return smallIntegerComponent<int16_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return smallIntegerComponent<uint16_t>(p, normalized);
    case TINYGLTF_COMPONENT_TYPE_INT:
      return float(load<int32_t>(p));
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return normalized ? float(double(load<uint32_t>(p)) / 4294967295.0)
                        : float(load<uint32_t>(p));
    default:
      return load<float>(p);
  }
}

std::string accessorPointer(int index) { return cat("/accessors/", index); }

/// The elements of an accessor as bytes: `count` elements of `elementSize` bytes, element i
/// at data + i * stride. Sparse accessors (and those without a view) are materialised.
struct Elements {
  const unsigned char* data = nullptr;
  size_t stride = 0;
  std::vector<unsigned char> owned;
};

Elements elements(const tinygltf::Model& model, int index, const std::string& file,
                  size_t elementSize) {
  const std::string ptr = accessorPointer(index);
  if (index < 0 || size_t(index) >= model.accessors.size())
    fail(file, ptr, cat("no such accessor (the file has ", model.accessors.size(), ")"));
  const tinygltf::Accessor& a = model.accessors[size_t(index)];
  Elements e;
  e.stride = elementSize;
  if (a.bufferView >= 0) {
    const ViewBytes view = viewBytes(model, a.bufferView, file, ptr + "/bufferView");
    const size_t viewStride = model.bufferViews[size_t(a.bufferView)].byteStride;
    if (viewStride != 0) {
      if (viewStride < elementSize)
        fail(file, cat("/bufferViews/", a.bufferView, "/byteStride"),
             cat("byteStride ", viewStride, " is shorter than the element of accessor ", index,
                 " (", elementSize, " bytes)"));
      e.stride = viewStride;
    }
    if (a.byteOffset > view.size)
      fail(file, ptr + "/byteOffset",
           cat("byteOffset ", a.byteOffset, " is past the end of buffer view ", a.bufferView, " (",
               view.size, " bytes)"));
    if (a.count > 0 && (a.count - 1 > (view.size - a.byteOffset) / e.stride ||
                        (a.count - 1) * e.stride + elementSize > view.size - a.byteOffset))
      fail(file, ptr + "/count",
           cat(a.count, " elements of ", elementSize, " bytes (stride ", e.stride,
               ") from byteOffset ", a.byteOffset, " run past the end of buffer view ",
               a.bufferView, " (", view.size, " bytes)"));
    e.data = view.data + a.byteOffset;
  }
  if (a.bufferView < 0 && !a.sparse.isSparse)
    fail(file, ptr + "/bufferView", "no bufferView (and not sparse): the accessor has no data");
  if (a.bufferView < 0 || a.sparse.isSparse) {
    // Materialise: the base (or zeros), then the sparse values over it. Zeros cost no file
    // bytes, so their size is bounded.
    if (a.bufferView < 0 && a.count > (size_t(1) << 26) / elementSize)
      fail(file, ptr + "/count",
           cat("count ", a.count, " of zeros (no bufferView) is over 64 MiB"));
    e.owned.assign(a.count * elementSize, 0);
    if (e.data)
      for (size_t i = 0; i < a.count; ++i)
        std::memcpy(&e.owned[i * elementSize], e.data + i * e.stride, elementSize);
    if (a.sparse.isSparse) {
      const std::string sp = ptr + "/sparse";
      const size_t n = size_t(std::max(a.sparse.count, 0));
      if (n == 0 || n > a.count)
        fail(file, sp + "/count", cat("count ", a.sparse.count, " outside [1, ", a.count, "]"));
      const int it = a.sparse.indices.componentType;
      const size_t is = componentBytes(it);
      if (it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
          it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        fail(file, sp + "/indices/componentType",
             cat("componentType ", it, " (expected 5121, 5123 or 5125)"));
      const ViewBytes iv =
          viewBytes(model, a.sparse.indices.bufferView, file, sp + "/indices/bufferView");
      const size_t io = size_t(std::max(a.sparse.indices.byteOffset, 0));
      if (io > iv.size || n > (iv.size - io) / is)
        fail(file, sp + "/indices/byteOffset",
             cat(n, " indices from byteOffset ", io, " run past the end of buffer view ",
                 a.sparse.indices.bufferView, " (", iv.size, " bytes)"));
      const ViewBytes vv =
          viewBytes(model, a.sparse.values.bufferView, file, sp + "/values/bufferView");
      const size_t vo = size_t(std::max(a.sparse.values.byteOffset, 0));
      if (vo > vv.size || n > (vv.size - vo) / elementSize)
        fail(file, sp + "/values/byteOffset",
             cat(n, " values from byteOffset ", vo, " run past the end of buffer view ",
                 a.sparse.values.bufferView, " (", vv.size, " bytes)"));
      for (size_t k = 0; k < n; ++k) {
        const unsigned char* ip = iv.data + io + k * is;
        const size_t target = it == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE    ? load<uint8_t>(ip)
                              : it == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? load<uint16_t>(ip)
                                                                             : load<uint32_t>(ip);
        if (target >= a.count)
          fail(file, sp + "/indices",
               cat("sparse index ", target, " (entry ", k, ") is out of range of the ", a.count,
                   " elements"));
        std::memcpy(&e.owned[target * elementSize], vv.data + vo + k * elementSize, elementSize);
      }
    }
    e.data = e.owned.data();
    e.stride = elementSize;
  }
  return e;
}

}  // namespace

ViewBytes viewBytes(const tinygltf::Model& model, int view, const std::string& file,
                    const std::string& pointer) {
  if (view < 0 || size_t(view) >= model.bufferViews.size())
    fail(
        file, pointer,
        cat("buffer view ", view, " does not exist (the file has ", model.bufferViews.size(), ")"));
  const tinygltf::BufferView& v = model.bufferViews[size_t(view)];
  const std::string vp = cat("/bufferViews/", view);
  if (v.buffer < 0 || size_t(v.buffer) >= model.buffers.size())
    fail(file, vp + "/buffer",
         cat("buffer ", v.buffer, " does not exist (the file has ", model.buffers.size(), ")"));
  const size_t have = model.buffers[size_t(v.buffer)].data.size();
  if (v.byteOffset > have || v.byteLength > have - v.byteOffset)
    fail(file, vp + "/byteLength",
         cat("bytes [", v.byteOffset, ", ", v.byteOffset + v.byteLength,
             ") run past the end of buffer ", v.buffer, " (", have, " bytes)"));
  return {model.buffers[size_t(v.buffer)].data.data() + v.byteOffset, v.byteLength};
}

LargeBuffer<float> readFloats(const tinygltf::Model& model, int index, const std::string& file,
                              int& components, bool normalizeIntegers) {
  if (index < 0 || size_t(index) >= model.accessors.size())
    fail(file, accessorPointer(index),
         cat("no such accessor (the file has ", model.accessors.size(), ")"));
  const tinygltf::Accessor& a = model.accessors[size_t(index)];
  components = typeComponents(a.type);
  const size_t bytes = componentBytes(a.componentType);
  if (components == 0) fail(file, accessorPointer(index) + "/type", cat("unknown type ", a.type));
  if (bytes == 0)
    fail(file, accessorPointer(index) + "/componentType",
         cat("unknown componentType ", a.componentType));
  const size_t elementSize = size_t(components) * bytes;
  const Elements e = elements(model, index, file, elementSize);
  const bool normalized =
      a.normalized || (normalizeIntegers && a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT);
  LargeBuffer<float> out;
  resizeOnHugePages(out, a.count * size_t(components));
  if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && e.stride == elementSize) {
    if (!out.empty()) std::memcpy(out.data(), e.data, out.size() * sizeof(float));
    return out;
  }
  for (size_t i = 0; i < a.count; ++i) {
    const unsigned char* p = e.data + i * e.stride;
    for (int c = 0; c < components; ++c)
      out[i * size_t(components) + size_t(c)] =
          component(p + size_t(c) * bytes, a.componentType, normalized);
  }
  return out;
}

LargeBuffer<uint32_t> readIndices(const tinygltf::Model& model, int index,
                                  const std::string& file) {
  if (index < 0 || size_t(index) >= model.accessors.size())
    fail(file, accessorPointer(index),
         cat("no such accessor (the file has ", model.accessors.size(), ")"));
  const tinygltf::Accessor& a = model.accessors[size_t(index)];
  if (a.type != TINYGLTF_TYPE_SCALAR)
    fail(file, accessorPointer(index) + "/type", "indices must be SCALAR");
  const int t = a.componentType;
  if (t != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && t != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
      t != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
    fail(file, accessorPointer(index) + "/componentType",
         cat("indices of componentType ", t, " (expected 5121, 5123 or 5125)"));
  const size_t bytes = componentBytes(t);
  const Elements e = elements(model, index, file, bytes);
  LargeBuffer<uint32_t> out;
  resizeOnHugePages(out, a.count);
  // In parallel: the index list of a large mesh is the largest array of the file.
  parallelForChunks(out.size(), size_t(1) << 18, [&](size_t, size_t b, size_t end) {
    if (t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT && e.stride == 4) {
      std::memcpy(out.data() + b, e.data + 4 * b, 4 * (end - b));
      return;
    }
    for (size_t i = b; i < end; ++i) {
      const unsigned char* p = e.data + i * e.stride;
      out[i] = t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE    ? load<uint8_t>(p)
               : t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? load<uint16_t>(p)
                                                             : load<uint32_t>(p);
    }
  });
  return out;
}

LargeBuffer<float> rgba(const LargeBuffer<float>& values, int components) {
  if (components == 4) return values;
  const size_t n = values.size() / size_t(components);
  LargeBuffer<float> out(4 * n, 1.0f);
  for (size_t i = 0; i < n; ++i)
    for (size_t c = 0; c < 3; ++c) out[4 * i + c] = values[3 * i + c];
  return out;
}

}  // namespace aperture::gltf
