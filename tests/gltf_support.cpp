#include "gltf_support.h"

#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <meshoptimizer.h>
#include <zlib.h>

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace aperture::test {

namespace {

using json = nlohmann::json;

/// Bytes of one buffer, each piece 4-byte aligned.
struct GltfBlob {
  std::vector<unsigned char> bytes;
  size_t add(const void* data, size_t size) {
    while (bytes.size() % 4) bytes.push_back(0);
    const size_t at = bytes.size();
    const auto* p = static_cast<const unsigned char*>(data);
    bytes.insert(bytes.end(), p, p + size);
    return at;
  }
};

std::string gltfStem(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  return dot == std::string::npos ? path : path.substr(0, dot);
}
std::string gltfBaseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

void writeGltfFile(const std::string& path, const void* data, size_t size) {
  std::ofstream out(path, std::ios::binary);
  out.write(static_cast<const char*>(data), std::streamsize(size));
  if (!out) throw std::runtime_error("gltf_support: cannot write " + path);
}

const char* gltfTypeName(int components) {
  switch (components) {
    case 1:
      return "SCALAR";
    case 2:
      return "VEC2";
    case 3:
      return "VEC3";
    default:
      return "VEC4";
  }
}

struct GltfWriter {
  const GltfScene& scene;
  GltfCompression compression;
  std::string path;
  json doc;
  GltfBlob blob;             // buffer 0
  size_t fallbackBytes = 0;  // meshopt: the uncompressed layout of buffer 1

  int addView(const void* data, size_t size, int stride, bool indices, bool triangles = false) {
    json view;
    if (compression == GltfCompression::Meshopt) {
      const size_t count = size / size_t(stride);
      std::vector<unsigned char> encoded;
      const char* mode = "ATTRIBUTES";
      if (indices) {
        const auto* idx = static_cast<const uint32_t*>(data);
        uint32_t vertices = 0;
        for (size_t i = 0; i < count; ++i) vertices = std::max(vertices, idx[i] + 1);
        // Triangle lists go through the index-buffer codec, anything else the sequence one.
        if (triangles) {
          encoded.resize(meshopt_encodeIndexBufferBound(count, vertices));
          encoded.resize(meshopt_encodeIndexBuffer(encoded.data(), encoded.size(), idx, count));
          mode = "TRIANGLES";
        } else {
          encoded.resize(meshopt_encodeIndexSequenceBound(count, vertices));
          encoded.resize(meshopt_encodeIndexSequence(encoded.data(), encoded.size(), idx, count));
          mode = "INDICES";
        }
      } else {
        encoded.resize(meshopt_encodeVertexBufferBound(count, size_t(stride)));
        encoded.resize(meshopt_encodeVertexBuffer(encoded.data(), encoded.size(), data, count,
                                                  size_t(stride)));
      }
      const size_t at = blob.add(encoded.data(), encoded.size());
      while (fallbackBytes % 4) ++fallbackBytes;
      view = {{"buffer", 1}, {"byteOffset", fallbackBytes}, {"byteLength", size}};
      fallbackBytes += size;
      json ext = {{"buffer", 0},          {"byteOffset", at}, {"byteLength", encoded.size()},
                  {"byteStride", stride}, {"count", count},   {"mode", mode}};
      if (!indices) view["byteStride"] = stride;
      view["extensions"]["EXT_meshopt_compression"] = ext;
    } else {
      const size_t at = blob.add(data, size);
      view = {{"buffer", 0}, {"byteOffset", at}, {"byteLength", size}};
    }
    doc["bufferViews"].push_back(view);
    return int(doc["bufferViews"].size() - 1);
  }

  int addAccessor(int view, int componentType, int components, size_t count,
                  const std::vector<float>* minmaxOf = nullptr) {
    json a = {
        {"componentType", componentType}, {"count", count}, {"type", gltfTypeName(components)}};
    if (view >= 0) a["bufferView"] = view;
    if (minmaxOf) {
      std::vector<float> lo(size_t(components), 1e30f), hi(size_t(components), -1e30f);
      for (size_t i = 0; i < minmaxOf->size(); ++i) {
        lo[i % size_t(components)] = std::min(lo[i % size_t(components)], (*minmaxOf)[i]);
        hi[i % size_t(components)] = std::max(hi[i % size_t(components)], (*minmaxOf)[i]);
      }
      a["min"] = lo;
      a["max"] = hi;
    }
    doc["accessors"].push_back(a);
    return int(doc["accessors"].size() - 1);
  }

  int floats(const std::vector<float>& v, int components, bool minmax = false) {
    const int view = addView(v.data(), v.size() * 4, components * 4, false);
    return addAccessor(view, 5126, components, v.size() / size_t(components),
                       minmax ? &v : nullptr);
  }

  json dracoPrimitive(const GltfPrimitive& p) {
    const size_t n = p.positions.size() / 3;
    draco::Mesh mesh;
    mesh.set_num_points(uint32_t(n));
    json ids, attributes;
    auto add = [&](draco::GeometryAttribute::Type type, const std::vector<float>& v, int components,
                   const char* name) {
      if (v.empty()) return;
      draco::GeometryAttribute ga;
      ga.Init(type, nullptr, uint8_t(components), draco::DT_FLOAT32, false,
              int64_t(sizeof(float)) * components, 0);
      const int id = mesh.AddAttribute(ga, true, uint32_t(n));
      draco::PointAttribute* a = mesh.attribute(id);
      for (size_t i = 0; i < n; ++i)
        a->SetAttributeValue(draco::AttributeValueIndex(uint32_t(i)), &v[i * size_t(components)]);
      ids[name] = a->unique_id();
      attributes[name] =
          addAccessor(-1, 5126, components, n, std::string(name) == "POSITION" ? &v : nullptr);
    };
    add(draco::GeometryAttribute::POSITION, p.positions, 3, "POSITION");
    add(draco::GeometryAttribute::NORMAL, p.normals, 3, "NORMAL");
    add(draco::GeometryAttribute::TEX_COORD, p.uv, 2, "TEXCOORD_0");
    add(draco::GeometryAttribute::COLOR, p.colors, 4, "COLOR_0");
    std::vector<uint32_t> order = p.indices;
    if (order.empty())
      for (uint32_t i = 0; i < n; ++i) order.push_back(i);
    for (size_t f = 0; f + 2 < order.size(); f += 3)
      mesh.AddFace({draco::PointIndex(order[f]), draco::PointIndex(order[f + 1]),
                    draco::PointIndex(order[f + 2])});
    draco::Encoder encoder;
    encoder.SetEncodingMethod(draco::MESH_SEQUENTIAL_ENCODING);
    draco::EncoderBuffer out;
    const draco::Status status = encoder.EncodeMeshToBuffer(mesh, &out);
    if (!status.ok()) throw std::runtime_error("draco: " + status.error_msg_string());
    const size_t at = blob.add(out.data(), out.size());
    doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", out.size()}});
    json prim = {{"attributes", attributes}, {"mode", 4}};
    prim["indices"] = addAccessor(-1, 5125, 1, order.size() / 3 * 3);
    prim["extensions"]["KHR_draco_mesh_compression"] = {
        {"bufferView", doc["bufferViews"].size() - 1}, {"attributes", ids}};
    return prim;
  }

  json primitive(const GltfPrimitive& p) {
    if (compression == GltfCompression::Draco && p.mode == 4) return dracoPrimitive(p);
    json prim = {{"attributes", {{"POSITION", floats(p.positions, 3, true)}}}};
    if (!p.normals.empty()) prim["attributes"]["NORMAL"] = floats(p.normals, 3);
    if (!p.uv.empty()) prim["attributes"]["TEXCOORD_0"] = floats(p.uv, 2);
    if (!p.colors.empty()) prim["attributes"]["COLOR_0"] = floats(p.colors, 4);
    if (!p.indices.empty()) {
      const int view = addView(p.indices.data(), p.indices.size() * 4, 4, true,
                               p.mode == 4 && p.indices.size() % 3 == 0);
      prim["indices"] = addAccessor(view, 5125, 1, p.indices.size());
    }
    if (p.mode != 4) prim["mode"] = p.mode;
    return prim;
  }

  void write() {
    doc["asset"] = {{"version", "2.0"}, {"generator", "aperture tests/gltf_support"}};
    doc["bufferViews"] = json::array();
    doc["accessors"] = json::array();
    for (const GltfMesh& m : scene.meshes) {
      json mesh = {{"primitives", json::array()}};
      if (!m.name.empty()) mesh["name"] = m.name;
      for (const GltfPrimitive& p : m.primitives) {
        json prim = primitive(p);
        if (p.material >= 0) prim["material"] = p.material;
        mesh["primitives"].push_back(prim);
      }
      doc["meshes"].push_back(mesh);
    }
    for (size_t i = 0; i < scene.materials.size(); ++i) {
      const GltfMaterial& m = scene.materials[i];
      json mat;
      if (!m.name.empty()) mat["name"] = m.name;
      mat["pbrMetallicRoughness"]["baseColorFactor"] = {m.baseColor.x, m.baseColor.y, m.baseColor.z,
                                                        m.baseColor.w};
      if (!m.png.empty() || !m.imageUri.empty()) {
        json image;
        if (!m.imageUri.empty()) {
          image["uri"] = m.imageUri;
        } else if (m.externalImage) {
          const std::string file = gltfStem(path) + "_image" + std::to_string(i) + ".png";
          writeGltfFile(file, m.png.data(), m.png.size());
          image["uri"] = gltfBaseName(file);
        } else {
          const size_t at = blob.add(m.png.data(), m.png.size());
          doc["bufferViews"].push_back(
              {{"buffer", 0}, {"byteOffset", at}, {"byteLength", m.png.size()}});
          image["bufferView"] = doc["bufferViews"].size() - 1;
          image["mimeType"] = "image/png";
        }
        doc["images"].push_back(image);
        json sampler = {{"wrapS", m.wrapS}, {"wrapT", m.wrapT}};
        if (m.magFilter >= 0) sampler["magFilter"] = m.magFilter;
        doc["samplers"].push_back(sampler);
        doc["textures"].push_back(
            {{"source", doc["images"].size() - 1}, {"sampler", doc["samplers"].size() - 1}});
        mat["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", doc["textures"].size() - 1}};
        if (m.texCoord != 0)
          mat["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = m.texCoord;
      }
      doc["materials"].push_back(mat);
    }
    for (const GltfCamera& c : scene.cameras) {
      json cam;
      if (c.orthographic) {
        cam["type"] = "orthographic";
        cam["orthographic"] = {
            {"xmag", c.xmag}, {"ymag", c.ymag}, {"znear", c.znear}, {"zfar", c.zfar}};
      } else {
        cam["type"] = "perspective";
        cam["perspective"] = {{"yfov", c.yfov}, {"znear", c.znear}};
        if (c.aspectRatio > 0) cam["perspective"]["aspectRatio"] = c.aspectRatio;
        if (c.zfar > 0) cam["perspective"]["zfar"] = c.zfar;
      }
      doc["cameras"].push_back(cam);
    }
    for (const GltfNode& n : scene.nodes) {
      json node = json::object();
      if (!n.name.empty()) node["name"] = n.name;
      if (n.mesh >= 0) node["mesh"] = n.mesh;
      if (n.camera >= 0) node["camera"] = n.camera;
      if (!n.children.empty()) node["children"] = n.children;
      if (n.matrix) {
        std::vector<double> m;
        for (int col = 0; col < 4; ++col)
          for (int row = 0; row < 4; ++row) m.push_back((*n.matrix)[col][row]);
        node["matrix"] = m;
      }
      if (n.translation)
        node["translation"] = {n.translation->x, n.translation->y, n.translation->z};
      if (n.rotation)
        node["rotation"] = {n.rotation->x, n.rotation->y, n.rotation->z, n.rotation->w};
      if (n.scale) node["scale"] = {n.scale->x, n.scale->y, n.scale->z};
      doc["nodes"].push_back(node);
    }
    doc["scenes"] = json::array({{{"nodes", scene.roots}}});
    doc["scene"] = 0;
    std::vector<std::string> used = scene.extensionsRequired, required = scene.extensionsRequired;
    if (compression == GltfCompression::Draco) {
      used.push_back("KHR_draco_mesh_compression");
      required.push_back("KHR_draco_mesh_compression");
    }
    if (compression == GltfCompression::Meshopt) {
      used.push_back("EXT_meshopt_compression");
      required.push_back("EXT_meshopt_compression");
    }
    if (!used.empty()) doc["extensionsUsed"] = used;
    if (!required.empty()) doc["extensionsRequired"] = required;
    while (blob.bytes.size() % 4) blob.bytes.push_back(0);
    const bool glb = path.size() > 4 && path.substr(path.size() - 4) == ".glb";
    json buffer = {{"byteLength", std::max<size_t>(blob.bytes.size(), 4)}};
    if (blob.bytes.empty()) blob.bytes.assign(4, 0);
    if (!glb) {
      const std::string bin = gltfStem(path) + ".bin";
      writeGltfFile(bin, blob.bytes.data(), blob.bytes.size());
      buffer["uri"] = gltfBaseName(bin);
    }
    doc["buffers"] = json::array({buffer});
    if (compression == GltfCompression::Meshopt)
      doc["buffers"].push_back(
          {{"byteLength", std::max<size_t>(fallbackBytes, 1)},
           {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
    std::string text = doc.dump(1);
    if (!glb) {
      writeGltfFile(path, text.data(), text.size());
      return;
    }
    while (text.size() % 4) text += ' ';
    std::vector<unsigned char> out;
    auto u32 = [&](uint32_t v) {
      unsigned char b[4];
      std::memcpy(b, &v, 4);
      out.insert(out.end(), b, b + 4);
    };
    out.insert(out.end(), {'g', 'l', 'T', 'F'});
    u32(2);
    u32(uint32_t(12 + 8 + text.size() + 8 + blob.bytes.size()));
    u32(uint32_t(text.size()));
    u32(0x4E4F534Au);
    out.insert(out.end(), text.begin(), text.end());
    u32(uint32_t(blob.bytes.size()));
    u32(0x004E4942u);
    out.insert(out.end(), blob.bytes.begin(), blob.bytes.end());
    writeGltfFile(path, out.data(), out.size());
  }
};

void pngChunkOf(std::vector<unsigned char>& out, const char* type,
                const std::vector<unsigned char>& data) {
  auto u32 = [&](uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<unsigned char>(v >> s));
  };
  u32(uint32_t(data.size()));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  u32(uint32_t(crc32(0, out.data() + start, uInt(out.size() - start))));
}

}  // namespace

std::string writeGltf(const GltfScene& scene, const std::string& path,
                      GltfCompression compression) {
  GltfWriter w{scene, compression, path, {}, {}, 0};
  w.write();
  return path;
}

void editGltf(const std::string& path, const std::function<void(nlohmann::json&)>& edit) {
  std::ifstream in(path);
  json doc = json::parse(in);
  edit(doc);
  const std::string text = doc.dump(1);
  writeGltfFile(path, text.data(), text.size());
}

std::string dataUri(const std::vector<unsigned char>& bytes) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out = "data:application/octet-stream;base64,";
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint32_t(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= uint32_t(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= bytes[i + 2];
    out += digits[(v >> 18) & 63];
    out += digits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? digits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? digits[v & 63] : '=';
  }
  return out;
}

int RawGltf::addView(const std::vector<unsigned char>& bytes, int stride) {
  while (bin.size() % 4) bin.push_back(0);
  json view = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes.size()}};
  if (stride > 0) view["byteStride"] = stride;
  bin.insert(bin.end(), bytes.begin(), bytes.end());
  doc["bufferViews"].push_back(view);
  return int(doc["bufferViews"].size() - 1);
}

int RawGltf::addAccessor(int view, int componentType, const std::string& type, size_t count,
                         bool normalized, size_t byteOffset) {
  json a = {{"componentType", componentType}, {"type", type}, {"count", count}};
  if (view >= 0) a["bufferView"] = view;
  if (normalized) a["normalized"] = true;
  if (byteOffset) a["byteOffset"] = byteOffset;
  doc["accessors"].push_back(a);
  return int(doc["accessors"].size() - 1);
}

void RawGltf::addMeshNode(const json& attributes, int indices, int mode) {
  json prim = {{"attributes", attributes}, {"mode", mode}};
  if (indices >= 0) prim["indices"] = indices;
  doc["meshes"].push_back({{"primitives", {prim}}});
  doc["nodes"].push_back({{"mesh", doc["meshes"].size() - 1}});
  if (!doc.contains("scenes")) doc["scenes"] = json::array({{{"nodes", json::array()}}});
  doc["scenes"][0]["nodes"].push_back(doc["nodes"].size() - 1);
}

std::string RawGltf::write(const std::string& path) const {
  json out = doc;
  out["asset"] = {{"version", "2.0"}};
  json buffers = doc.value("buffers", json::array());
  if (!bin.empty())
    buffers.insert(buffers.begin(), json({{"byteLength", bin.size()}, {"uri", dataUri(bin)}}));
  if (!buffers.empty()) out["buffers"] = buffers;
  const std::string text = out.dump(1);
  writeGltfFile(path, text.data(), text.size());
  return path;
}

std::vector<unsigned char> checkerPng(int size, int cells) {
  std::vector<unsigned char> raw;
  for (int y = 0; y < size; ++y) {
    raw.push_back(0);  // filter: none
    for (int x = 0; x < size; ++x) {
      const bool white = ((x * cells / size) + (y * cells / size)) % 2 == 1;
      for (int c = 0; c < 3; ++c) raw.push_back(white ? 255 : 0);
    }
  }
  std::vector<unsigned char> z(compressBound(uLong(raw.size())));
  uLongf zsize = uLongf(z.size());
  if (compress(z.data(), &zsize, raw.data(), uLong(raw.size())) != Z_OK)
    throw std::runtime_error("checkerPng: zlib failed");
  z.resize(zsize);
  std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<unsigned char> ihdr;
  for (int v : {size, size})
    for (int s = 24; s >= 0; s -= 8) ihdr.push_back(static_cast<unsigned char>(v >> s));
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});  // 8-bit RGB, deflate, no filter, no interlace
  pngChunkOf(png, "IHDR", ihdr);
  pngChunkOf(png, "IDAT", z);
  pngChunkOf(png, "IEND", {});
  return png;
}

GltfScene issue41Scene() {
  GltfScene s;
  GltfPrimitive quad;
  quad.positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  quad.indices = {0, 1, 2, 0, 2, 3};
  quad.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  quad.uv = {0, 1, 1, 1, 1, 0, 0, 0};
  quad.colors = {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1, 1, 0.5f};
  quad.material = 0;
  GltfPrimitive tri;
  tri.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.colors = {0.25f, 0.5f, 0.75f, 1, 0.25f, 0.5f, 0.75f, 1, 0.25f, 0.5f, 0.75f, 1};
  tri.uv = {0, 0, 1, 0, 0, 1};
  tri.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  tri.material = 1;
  s.meshes = {{"quad", {quad}}, {"tri", {tri}}};
  GltfMaterial checker;
  checker.name = "checker";
  checker.png = checkerPng(8, 2);
  checker.magFilter = 9728;
  GltfMaterial red;
  red.name = "red";
  red.baseColor = {1, 0, 0, 1};
  s.materials = {checker, red};
  s.cameras = {GltfCamera{}};
  s.cameras[0].aspectRatio = 1.5;
  s.cameras[0].zfar = 100;
  s.nodes.resize(7);
  s.nodes[0].name = "root";
  s.nodes[0].translation = glm::dvec3(1, 2, 3);
  s.nodes[0].rotation = glm::angleAxis(0.5, glm::normalize(glm::dvec3(0, 1, 0.5)));
  s.nodes[0].scale = glm::dvec3(2, 2, 2);
  s.nodes[0].children = {1, 2, 3};
  s.nodes[1].name = "quad_a";
  s.nodes[1].mesh = 0;
  s.nodes[1].translation = glm::dvec3(0, 0, -5);
  s.nodes[2].name = "quad_b";
  s.nodes[2].mesh = 0;
  glm::dmat4 m(1.0);
  m[0] = glm::dvec4(0, 1, 0, 0);
  m[1] = glm::dvec4(-1, 0, 0, 0);
  m[2] = glm::dvec4(0, 0, 1.5, 0);
  m[3] = glm::dvec4(3, -1, 0.25, 1);
  s.nodes[2].matrix = m;
  s.nodes[3].name = "group";
  s.nodes[3].rotation = glm::angleAxis(1.0, glm::dvec3(1, 0, 0));
  s.nodes[3].children = {4, 5};
  s.nodes[4].name = "quad_c";
  s.nodes[4].mesh = 0;
  s.nodes[4].scale = glm::dvec3(0.5, 1, 3);
  s.nodes[5].name = "tri";
  s.nodes[5].mesh = 1;
  s.nodes[5].translation = glm::dvec3(-2, 0, 0);
  s.nodes[6].name = "camera";
  s.nodes[6].camera = 0;
  s.nodes[6].translation = glm::dvec3(0, 0, 10);
  s.roots = {0, 6};
  return s;
}

}  // namespace aperture::test
