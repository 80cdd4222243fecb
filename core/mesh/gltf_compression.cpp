// The two geometry compression extensions of glTF: KHR_draco_mesh_compression (decoded by
// libdraco) and EXT_meshopt_compression (meshoptimizer's decoders and filters).
#include <draco/compression/decode.h>
#include <meshoptimizer.h>

#include <memory>

#include "core/mesh/gltf.h"
#include "core/util/error.h"

namespace aperture::gltf {

namespace {

const tinygltf::Value& member(const tinygltf::Value& object, const char* key) {
  static const tinygltf::Value none;
  return object.IsObject() && object.Has(key) ? object.Get(key) : none;
}

int integerOf(const tinygltf::Value& v, int fallback) {
  return v.IsNumber() || v.IsInt() ? v.GetNumberAsInt() : fallback;
}

}  // namespace

void decodeMeshoptViews(tinygltf::Model& model, const std::string& file) {
  const size_t views = model.bufferViews.size();
  for (size_t v = 0; v < views; ++v) {
    const auto it = model.bufferViews[v].extensions.find("EXT_meshopt_compression");
    if (it == model.bufferViews[v].extensions.end()) continue;
    const std::string p = cat("/bufferViews/", v, "/extensions/EXT_meshopt_compression");
    const tinygltf::Value& e = it->second;
    const int buffer = integerOf(member(e, "buffer"), -1);
    const size_t offset = size_t(std::max(integerOf(member(e, "byteOffset"), 0), 0));
    const size_t length = size_t(std::max(integerOf(member(e, "byteLength"), 0), 0));
    const size_t stride = size_t(std::max(integerOf(member(e, "byteStride"), 0), 0));
    const size_t count = size_t(member(e, "count").IsNumber() || member(e, "count").IsInt()
                                    ? std::max(member(e, "count").GetNumberAsDouble(), 0.0)
                                    : 0.0);
    const std::string mode =
        member(e, "mode").IsString() ? member(e, "mode").Get<std::string>() : "";
    const std::string filter =
        member(e, "filter").IsString() ? member(e, "filter").Get<std::string>() : "NONE";
    if (buffer < 0 || size_t(buffer) >= model.buffers.size())
      fail(file, p + "/buffer", cat("buffer ", buffer, " does not exist"));
    const std::vector<unsigned char>& source = model.buffers[size_t(buffer)].data;
    if (offset > source.size() || length > source.size() - offset)
      fail(file, p + "/byteLength",
           cat("bytes [", offset, ", ", offset + length, ") run past the end of buffer ", buffer,
               " (", source.size(), " bytes)"));
    // meshoptimizer's codecs compress by at most 64:1 (a 4-byte header per 256 zero bytes of
    // vertex data); a count beyond a generous multiple of that is refused before allocating.
    if (count > (size_t(1) << 31) / std::max<size_t>(stride, 1) ||
        count * stride > 256 * length + 65536)
      fail(file, p + "/count",
           cat(count, " elements of ", stride, " bytes cannot come from ", length,
               " compressed bytes"));
    tinygltf::Buffer decoded;
    decoded.data.resize(count * stride);
    const unsigned char* src = source.data() + offset;
    int status = -1;
    if (mode == "ATTRIBUTES") {
      if (stride == 0 || stride > 256 || stride % 4)
        fail(file, p + "/byteStride",
             cat("byteStride ", stride, " (ATTRIBUTES: a multiple of 4 up to 256)"));
      status = meshopt_decodeVertexBuffer(decoded.data.data(), count, stride, src, length);
    } else if (mode == "TRIANGLES" || mode == "INDICES") {
      if (stride != 2 && stride != 4)
        fail(file, p + "/byteStride", cat("byteStride ", stride, " (", mode, ": 2 or 4)"));
      if (mode == "TRIANGLES") {
        if (count % 3)
          fail(file, p + "/count", cat("count ", count, " (TRIANGLES: a multiple of 3)"));
        status = meshopt_decodeIndexBuffer(decoded.data.data(), count, stride, src, length);
      } else {
        status = meshopt_decodeIndexSequence(decoded.data.data(), count, stride, src, length);
      }
      if (filter != "NONE") fail(file, p + "/filter", cat("filter ", filter, " on ", mode));
    } else {
      fail(file, p + "/mode", cat("unknown mode '", mode, "'"));
    }
    if (status != 0)
      fail(file, p, cat("the meshopt data does not decode (meshoptimizer error ", status, ")"));
    if (filter == "OCTAHEDRAL") {
      if (stride != 4 && stride != 8)
        fail(file, p + "/byteStride", cat("byteStride ", stride, " (OCTAHEDRAL: 4 or 8)"));
      meshopt_decodeFilterOct(decoded.data.data(), count, stride);
    } else if (filter == "QUATERNION") {
      if (stride != 8)
        fail(file, p + "/byteStride", cat("byteStride ", stride, " (QUATERNION: 8)"));
      meshopt_decodeFilterQuat(decoded.data.data(), count, stride);
    } else if (filter == "EXPONENTIAL") {
      if (stride % 4)
        fail(file, p + "/byteStride",
             cat("byteStride ", stride, " (EXPONENTIAL: a multiple of 4)"));
      meshopt_decodeFilterExp(decoded.data.data(), count, stride);
    } else if (filter != "NONE") {
      fail(file, p + "/filter", cat("unknown filter '", filter, "'"));
    }
    tinygltf::BufferView& view = model.bufferViews[v];
    view.buffer = int(model.buffers.size());
    view.byteOffset = 0;
    model.buffers.push_back(std::move(decoded));
  }
}

PrimitiveData decodeDraco(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                          const std::string& file, const std::string& pointer, bool normals,
                          bool texcoords, bool colors) {
  const std::string p = pointer + "/extensions/KHR_draco_mesh_compression";
  const tinygltf::Value& ext = primitive.extensions.at("KHR_draco_mesh_compression");
  const ViewBytes bytes =
      viewBytes(model, integerOf(member(ext, "bufferView"), -1), file, p + "/bufferView");
  if (primitive.mode != TINYGLTF_MODE_TRIANGLES)
    fail(file, pointer + "/mode", cat("mode ", primitive.mode, " with Draco (triangles only)"));
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(bytes.data), bytes.size);
  draco::Decoder decoder;
  auto result = decoder.DecodeMeshFromBuffer(&buffer);
  if (!result.ok())
    fail(file, p + "/bufferView",
         cat("the Draco data does not decode: ", result.status().error_msg_string()));
  const std::unique_ptr<draco::Mesh> mesh = std::move(result).value();
  if (!mesh) fail(file, p + "/bufferView", "the Draco data holds no mesh");
  PrimitiveData d;
  d.vertexCount = mesh->num_points();
  const tinygltf::Value& ids = member(ext, "attributes");
  // Reads attribute `name` (its unique id in the extension) as `want` floats per point.
  auto read = [&](const char* name, int want, int alt) {
    LargeBuffer<float> out;
    const tinygltf::Value& id = member(ids, name);
    if (!id.IsNumber() && !id.IsInt()) return out;
    const draco::PointAttribute* a = mesh->GetAttributeByUniqueId(uint32_t(id.GetNumberAsInt()));
    if (!a)
      fail(file, cat(p, "/attributes/", name), cat("no Draco attribute ", id.GetNumberAsInt()));
    // glTF's attributes are numbers: a bool (or untyped) attribute is refused before draco's
    // conversion reads its bytes as bool, which any byte but 0 and 1 makes undefined.
    const draco::DataType type = a->data_type();
    if (type == draco::DT_BOOL || type == draco::DT_INVALID || type >= draco::DT_TYPES_COUNT)
      fail(file, cat(p, "/attributes/", name), "a Draco attribute of a type that is no number");
    const int n = a->num_components();
    if (n != want && n != alt)
      fail(file, cat(p, "/attributes/", name), cat("a Draco attribute of ", n, " components"));
    out.resize(d.vertexCount * size_t(n));
    for (draco::PointIndex i(0); i < mesh->num_points(); ++i)
      if (!a->ConvertValue<float>(a->mapped_index(i), int8_t(n),
                                  &out[size_t(i.value()) * size_t(n)]))
        fail(file, cat(p, "/attributes/", name), "the Draco attribute does not convert to float");
    if (n == 3 && alt == 4) out = rgba(out, 3);
    return out;
  };
  d.positions = read("POSITION", 3, 3);
  if (d.positions.empty()) fail(file, p + "/attributes", "no POSITION");
  if (normals) d.normals = read("NORMAL", 3, 3);
  if (texcoords) d.texcoords = read("TEXCOORD_0", 2, 2);
  if (colors) d.colors = read("COLOR_0", 3, 4);
  d.indexed = true;
  d.indices.resize(3 * size_t(mesh->num_faces()));
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
    const draco::Mesh::Face& face = mesh->face(f);
    for (size_t c = 0; c < 3; ++c) {
      const uint32_t index = face[c].value();
      if (index >= d.vertexCount)
        fail(file, p + "/bufferView",
             cat("Draco index ", index, " is out of range of its ", d.vertexCount, " points"));
      d.indices[3 * size_t(f.value()) + c] = index;
    }
  }
  return d;
}

}  // namespace aperture::gltf
