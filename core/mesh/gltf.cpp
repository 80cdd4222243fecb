// The glTF 2.0 loader: reads the file (tinygltf parses the JSON and loads the buffers; its
// image decoding is replaced by a callback that keeps the bytes for OpenImageIO), then builds
// the SceneFile: the node hierarchy of the chosen scene, one Mesh per glTF mesh, materials,
// base colour textures and cameras.
//
// Extensions: KHR_mesh_quantization, KHR_draco_mesh_compression and EXT_meshopt_compression
// are supported. A required extension that only changes how a texture is stored or mapped
// (KHR_texture_basisu, EXT_texture_webp, EXT_texture_avif, KHR_texture_transform,
// KHR_materials_pbrSpecularGlossiness) marks the materials that use it (Material::unsupported)
// while the geometry loads; any other required extension is refused, naming it.
#include "core/mesh/gltf.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "core/mesh/scene_file.h"
#include "core/util/error.h"
#include "core/util/huge_pages.h"
#include "core/util/mapped_file.h"
#include "core/util/parallel.h"

namespace aperture {

namespace gltf {

void fail(const std::string& file, const std::string& pointer, const std::string& what) {
  if (pointer.empty()) throw Error(cat(file, ": ", what));
  throw Error(cat(file, ": ", pointer, ": ", what));
}

bool isDataUri(const std::string& uri) { return uri.rfind("data:", 0) == 0; }

std::string resolveUri(const std::string& baseDir, const std::string& uri) {
  std::string decoded;
  for (size_t i = 0; i < uri.size(); ++i) {
    auto hex = [](char c) -> int {
      if (c >= '0' && c <= '9') return c - '0';
      if (c >= 'a' && c <= 'f') return c - 'a' + 10;
      if (c >= 'A' && c <= 'F') return c - 'A' + 10;
      return -1;
    };
    if (uri[i] == '%' && i + 2 < uri.size() && hex(uri[i + 1]) >= 0 && hex(uri[i + 2]) >= 0) {
      decoded += char(hex(uri[i + 1]) * 16 + hex(uri[i + 2]));
      i += 2;
    } else {
      decoded += uri[i];
    }
  }
  if (!decoded.empty() && decoded[0] == '/') return decoded;
  return baseDir + decoded;
}

}  // namespace gltf

namespace {

using namespace gltf;

/// Required extensions that change only how a material's texture is stored or mapped: the
/// geometry loads, the materials that use them are marked unsupported.
constexpr const char* kTextureOnlyExtensions[] = {"KHR_texture_basisu", "EXT_texture_webp",
                                                  "EXT_texture_avif", "KHR_texture_transform",
                                                  "KHR_materials_pbrSpecularGlossiness"};
constexpr const char* kSupportedExtensions[] = {
    "KHR_mesh_quantization", "KHR_draco_mesh_compression", "EXT_meshopt_compression"};

bool contains(const char* const* begin, const char* const* end, const std::string& name) {
  return std::any_of(begin, end, [&](const char* s) { return name == s; });
}

uint32_t readU32(const unsigned char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

/// The JSON text and BIN chunk of a file in memory (a .glb container or .gltf text).
struct Container {
  const char* json = nullptr;
  size_t jsonSize = 0;
  const unsigned char* bin = nullptr;
  size_t binSize = 0;
  bool glb = false;
};

Container splitContainer(const char* data, size_t size, const std::string& file) {
  Container c;
  const auto* bytes = reinterpret_cast<const unsigned char*>(data);
  if (size < 4 || std::memcmp(data, "glTF", 4) != 0) {
    c.json = data;
    c.jsonSize = size;
    return c;
  }
  c.glb = true;
  if (size < 20) fail(file, "", cat("a GLB file of ", size, " bytes (its header needs 20)"));
  const uint32_t version = readU32(bytes + 4), length = readU32(bytes + 8);
  if (version != 2) fail(file, "", cat("GLB version ", version, " (expected 2)"));
  if (length > size || length < 20)
    fail(file, "", cat("the GLB header gives a length of ", length, " bytes; the file has ", size));
  const uint32_t jsonLength = readU32(bytes + 12), jsonType = readU32(bytes + 16);
  if (jsonType != 0x4E4F534Au) fail(file, "", "the first GLB chunk is not JSON (type 0x4E4F534A)");
  if (jsonLength > length - 20)
    fail(file, "", cat("the GLB JSON chunk of ", jsonLength, " bytes runs past the file"));
  c.json = data + 20;
  c.jsonSize = jsonLength;
  size_t at = 20 + size_t(jsonLength);
  at = (at + 3) & ~size_t(3);
  if (at + 8 <= length) {
    const uint32_t binLength = readU32(bytes + at), binType = readU32(bytes + at + 4);
    if (binType == 0x004E4942u) {
      if (binLength > length - at - 8)
        fail(file, "", cat("the GLB BIN chunk of ", binLength, " bytes runs past the file"));
      c.bin = bytes + at + 8;
      c.binSize = binLength;
    }
  }
  return c;
}

/// The image "decoder" given to tinygltf: keeps the encoded bytes of embedded images (buffer
/// views, data URIs) for OpenImageIO, decodes nothing. External images keep only their uri.
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                    const unsigned char* bytes, int size, void*) {
  if (image->uri.empty() && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

void appendU32(std::string& s, uint32_t v) {
  char b[4];
  std::memcpy(b, &v, 4);
  s.append(b, 4);
}

/// Parses the file with tinygltf after checking it (gltf_checks.cpp) and applying the rewrites
/// the checks asked for.
tinygltf::Model parse(const char* data, size_t size, const Source& base) {
  const Container c = splitContainer(data, size, base.file);
  Source source = base;
  source.glb = c.glb;
  source.binChunkBytes = c.binSize;
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(c.json, c.json + c.jsonSize);
  } catch (const nlohmann::json::exception& e) {
    fail(base.file, "", cat("invalid JSON: ", e.what()));
  }
  const Rewrites rewrites = checkDocument(doc, source);
  std::string text;
  const bool rewrite = !rewrites.emptyFallbackBuffers.empty() || !rewrites.dracoPrimitives.empty();
  if (rewrite) {
    for (size_t b : rewrites.emptyFallbackBuffers) {
      doc["buffers"][b]["uri"] = "data:application/octet-stream;base64,AA==";
      doc["buffers"][b]["byteLength"] = 1;
    }
    for (const auto& [m, p] : rewrites.dracoPrimitives)
      doc["meshes"][m]["primitives"][p].erase("indices");
    text = doc.dump();
  }
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&keepImageBytes, nullptr);
  std::string err, warn;
  bool ok = false;
  try {
    if (!c.glb) {
      const std::string& json = rewrite ? text : std::string(c.json, c.jsonSize);
      ok = loader.LoadASCIIFromString(&model, &err, &warn, json.data(),
                                      static_cast<unsigned int>(json.size()), base.baseDir);
    } else if (!rewrite) {
      ok = loader.LoadBinaryFromMemory(&model, &err, &warn,
                                       reinterpret_cast<const unsigned char*>(data),
                                       static_cast<unsigned int>(size), base.baseDir);
    } else {
      while (text.size() % 4) text += ' ';
      std::string glb = "glTF";
      appendU32(glb, 2);
      const size_t binPadded = (c.binSize + 3) & ~size_t(3);
      appendU32(glb, uint32_t(12 + 8 + text.size() + (c.bin ? 8 + binPadded : 0)));
      appendU32(glb, uint32_t(text.size()));
      appendU32(glb, 0x4E4F534Au);
      glb += text;
      if (c.bin) {
        appendU32(glb, uint32_t(binPadded));
        appendU32(glb, 0x004E4942u);
        glb.append(reinterpret_cast<const char*>(c.bin), c.binSize);
        glb.append(binPadded - c.binSize, '\0');
      }
      ok = loader.LoadBinaryFromMemory(&model, &err, &warn,
                                       reinterpret_cast<const unsigned char*>(glb.data()),
                                       static_cast<unsigned int>(glb.size()), base.baseDir);
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail(base.file, "", cat("tinygltf: ", e.what()));
  }
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    fail(base.file, "", cat("tinygltf: ", err));
  }
  return model;
}

glm::dmat4 localFromNode(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) {
    glm::dmat4 m;
    for (int col = 0; col < 4; ++col)
      for (int row = 0; row < 4; ++row) m[col][row] = node.matrix[size_t(4 * col + row)];
    return m;
  }
  glm::dmat4 t(1.0), r(1.0), s(1.0);
  if (node.translation.size() == 3)
    t[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
  if (node.rotation.size() == 4)
    r = glm::mat4_cast(
        glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]));
  if (node.scale.size() == 3) {
    s[0][0] = node.scale[0];
    s[1][1] = node.scale[1];
    s[2][2] = node.scale[2];
  }
  return t * r * s;
}

/// The triangles of a primitive's vertex sequence `order` (its indices, or 0..n-1) in `mode`.
void triangulate(int mode, const LargeBuffer<uint32_t>& order, LargeBuffer<uint32_t>& out) {
  const size_t n = order.size();
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    out.insert(out.end(), order.begin(), order.begin() + std::ptrdiff_t(n - n % 3));
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    // glTF 2.0, 3.7.2.1: triangle i is (v_i, v_{i+(1+i%2)}, v_{i+(2-i%2)}).
    for (size_t i = 0; i + 2 < n; ++i) {
      out.push_back(order[i]);
      out.push_back(order[i + 1 + i % 2]);
      out.push_back(order[i + 2 - i % 2]);
    }
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    // Triangle i is (v_{i+1}, v_{i+2}, v_0).
    for (size_t i = 0; i + 2 < n; ++i) {
      out.push_back(order[i + 1]);
      out.push_back(order[i + 2]);
      out.push_back(order[0]);
    }
  }
}

/// Elements per task of the parallel copies below: large enough that a task's overhead is lost.
constexpr size_t kCopyChunk = size_t(1) << 18;

/// Copies `n` values from `from` to `to` on every core (the loader's copies of a large mesh
/// are memory-bound; one thread reaches about a third of the machine's bandwidth).
template <class T>
void parallelCopy(const T* from, size_t n, T* to) {
  parallelForChunks(n, kCopyChunk, [&](size_t, size_t b, size_t e) {
    std::memcpy(to + b, from + b, (e - b) * sizeof(T));
  });
}

/// The position of the first index >= `vertices`, or indices.size() when none is (in parallel).
size_t firstIndexOutOfRange(const LargeBuffer<uint32_t>& indices, size_t vertices) {
  std::atomic<size_t> first{indices.size()};
  parallelForChunks(indices.size(), kCopyChunk, [&](size_t, size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      if (indices[i] >= vertices) {
        size_t seen = first.load();
        while (i < seen && !first.compare_exchange_weak(seen, i)) {
        }
        return;
      }
  });
  return first.load();
}

struct Builder {
  const tinygltf::Model& model;
  const std::string& file;
  const LoadOptions& options;
  SceneFile& scene;
  uint32_t defaultMaterial = 0;

  PrimitiveData readPrimitive(const tinygltf::Primitive& prim, const std::string& pp) {
    if (prim.extensions.count("KHR_draco_mesh_compression"))
      return decodeDraco(model, prim, file, pp, options.vertexNormals, options.texcoords,
                         options.vertexColors);
    PrimitiveData d;
    const auto position = prim.attributes.find("POSITION");
    if (position == prim.attributes.end()) fail(file, pp + "/attributes", "no POSITION");
    int components = 0;
    d.positions = readFloats(model, position->second, file, components);
    if (components != 3)
      fail(file, cat("/accessors/", position->second, "/type"), "POSITION must be VEC3");
    d.vertexCount = d.positions.size() / 3;
    auto attribute = [&](const char* name, int want3, int want4, bool normalize) {
      LargeBuffer<float> values;
      const auto it = prim.attributes.find(name);
      if (it == prim.attributes.end()) return values;
      values = readFloats(model, it->second, file, components, normalize);
      if (components != want3 && components != want4)
        fail(file, cat("/accessors/", it->second, "/type"),
             cat(name, " with ", components, " components"));
      if (values.size() / size_t(components) != d.vertexCount)
        fail(file, cat(pp, "/attributes/", name),
             cat("accessor ", it->second, " has ", values.size() / size_t(components),
                 " elements; POSITION has ", d.vertexCount));
      if (components == 3 && want4 == 4) values = rgba(values, 3);
      return values;
    };
    if (options.vertexNormals) d.normals = attribute("NORMAL", 3, 3, false);
    if (options.texcoords) d.texcoords = attribute("TEXCOORD_0", 2, 2, false);
    if (options.vertexColors) d.colors = attribute("COLOR_0", 3, 4, true);
    if (prim.indices >= 0) {
      d.indexed = true;
      d.indices = readIndices(model, prim.indices, file);
      const size_t bad = firstIndexOutOfRange(d.indices, d.vertexCount);
      if (bad < d.indices.size())
        fail(file, cat("/accessors/", prim.indices),
             cat("index ", d.indices[bad], " (element ", bad, ") is out of range of the ",
                 d.vertexCount, " vertices of ", pp));
    }
    return d;
  }

  Mesh buildMesh(size_t m) {
    const tinygltf::Mesh& gm = model.meshes[m];
    Mesh mesh;
    mesh.name = cat(file, "#/meshes/", m);
    std::vector<PrimitiveData> prims;
    std::vector<LargeBuffer<uint32_t>> triangles;
    std::vector<uint32_t> materials;
    size_t vertices = 0, indices = 0;
    bool anyNormals = false, anyUv = false, anyColors = false;
    for (size_t p = 0; p < gm.primitives.size(); ++p) {
      const tinygltf::Primitive& prim = gm.primitives[p];
      const std::string pp = cat("/meshes/", m, "/primitives/", p);
      if (prim.mode >= 0 && prim.mode <= 3) {
        ++scene.skippedPrimitives;
        continue;
      }
      if (prim.mode > 6 || prim.mode < 0) fail(file, pp + "/mode", cat("unknown mode ", prim.mode));
      PrimitiveData d = readPrimitive(prim, pp);
      LargeBuffer<uint32_t> order = std::move(d.indices);
      if (!d.indexed) {
        order.resize(d.vertexCount);
        for (size_t i = 0; i < order.size(); ++i) order[i] = uint32_t(i);
      }
      LargeBuffer<uint32_t> tri;
      if (prim.mode == TINYGLTF_MODE_TRIANGLES) {  // the list itself: no copy
        order.resize(order.size() - order.size() % 3);
        tri = std::move(order);
      } else {
        triangulate(prim.mode, order, tri);
      }
      if (vertices + d.vertexCount > UINT32_MAX)
        fail(file, cat("/meshes/", m), "more than 2^32 - 1 vertices");
      if (vertices > 0) {
        const uint32_t offset = uint32_t(vertices);
        parallelForChunks(tri.size(), kCopyChunk, [&](size_t, size_t b, size_t e) {
          for (size_t i = b; i < e; ++i) tri[i] += offset;
        });
      }
      vertices += d.vertexCount;
      indices += tri.size();
      anyNormals |= !d.normals.empty();
      anyUv |= !d.texcoords.empty();
      anyColors |= !d.colors.empty();
      materials.push_back(prim.material >= 0 ? uint32_t(prim.material) : defaultMaterial);
      prims.push_back(std::move(d));
      triangles.push_back(std::move(tri));
    }
    mesh.vertexCount = vertices;
    if (prims.size() == 1) {
      // One primitive (the large meshes): its arrays become the mesh's, uncopied.
      mesh.positions = std::move(prims[0].positions);
      mesh.indices = std::move(triangles[0]);
    } else {
      resizeOnHugePages(mesh.positions, 3 * vertices);
      resizeOnHugePages(mesh.indices, indices);
    }
    const bool moved = prims.size() == 1;
    if (anyNormals) mesh.vertexNormals.assign(3 * vertices, 0.0f);
    if (anyUv) mesh.texcoords.assign(2 * vertices, 0.0f);
    if (anyColors) mesh.vertexColors.assign(4 * vertices, 1.0f);
    if (options.materials) mesh.faceMaterials.reserve(indices / 3);
    size_t v = 0, t = 0;
    for (size_t k = 0; k < prims.size(); ++k) {
      const PrimitiveData& d = prims[k];
      if (!moved) parallelCopy(d.positions.data(), d.positions.size(), &mesh.positions[3 * v]);
      if (!d.normals.empty())
        std::copy(d.normals.begin(), d.normals.end(),
                  mesh.vertexNormals.begin() + std::ptrdiff_t(3 * v));
      if (!d.texcoords.empty())
        std::copy(d.texcoords.begin(), d.texcoords.end(),
                  mesh.texcoords.begin() + std::ptrdiff_t(2 * v));
      if (!d.colors.empty())
        std::copy(d.colors.begin(), d.colors.end(),
                  mesh.vertexColors.begin() + std::ptrdiff_t(4 * v));
      const size_t corners = moved ? indices : triangles[k].size();  // moved: now the mesh's
      if (!moved) parallelCopy(triangles[k].data(), corners, &mesh.indices[t]);
      if (options.materials)
        mesh.faceMaterials.insert(mesh.faceMaterials.end(), corners / 3, materials[k]);
      v += d.vertexCount;
      t += corners;
      prims[k] = PrimitiveData();  // each primitive's arrays go as soon as they are copied
      triangles[k] = LargeBuffer<uint32_t>();
    }
    mesh.stats.sourceFaces = indices / 3;
    return mesh;
  }
};

bool usesExtension(const tinygltf::Model& model, const tinygltf::Material& material,
                   const std::string& ext) {
  if (material.extensions.count(ext)) return true;
  const tinygltf::TextureInfo& info = material.pbrMetallicRoughness.baseColorTexture;
  if (info.index < 0) return false;
  if (info.extensions.count(ext)) return true;
  return size_t(info.index) < model.textures.size() &&
         model.textures[size_t(info.index)].extensions.count(ext);
}

TextureWrap wrapOf(int mode) {
  if (mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return TextureWrap::ClampToEdge;
  if (mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return TextureWrap::MirroredRepeat;
  return TextureWrap::Repeat;
}

SceneFile buildScene(tinygltf::Model& model, const Source& source, size_t fileBytes,
                     const LoadOptions& options) {
  const std::string& file = source.file;
  SceneFile scene;
  scene.path = file;
  scene.fileBytes = fileBytes;
  for (const tinygltf::Buffer& b : model.buffers)
    if (!b.uri.empty() && !isDataUri(b.uri)) scene.fileBytes += b.data.size();

  std::vector<std::string> texturesOnly;
  for (size_t i = 0; i < model.extensionsRequired.size(); ++i) {
    const std::string& ext = model.extensionsRequired[i];
    if (contains(std::begin(kSupportedExtensions), std::end(kSupportedExtensions), ext)) continue;
    if (contains(std::begin(kTextureOnlyExtensions), std::end(kTextureOnlyExtensions), ext)) {
      texturesOnly.push_back(ext);
      continue;
    }
    fail(file, cat("/extensionsRequired/", i),
         cat("required extension ", ext,
             " is not supported (supported: KHR_mesh_quantization, KHR_draco_mesh_compression, "
             "EXT_meshopt_compression; texture-only ones mark their materials)"));
  }
  decodeMeshoptViews(model, file);

  // The scene.
  int sceneIndex = options.gltfScene ? *options.gltfScene : std::max(model.defaultScene, 0);
  if (sceneIndex < 0 || size_t(sceneIndex) >= std::max<size_t>(model.scenes.size(), 1) ||
      (model.scenes.empty() && options.gltfScene))
    fail(file, "/scenes",
         cat("scene ", sceneIndex, " is out of range: the file has ", model.scenes.size(),
             " scenes"));

  // Materials and textures.
  bool needDefault = false;
  for (const tinygltf::Mesh& m : model.meshes)
    for (const tinygltf::Primitive& p : m.primitives) needDefault |= p.material < 0 && p.mode > 3;
  std::vector<int> textureOf(model.textures.size(), -1);
  for (size_t i = 0; i < model.materials.size(); ++i) {
    const tinygltf::Material& gm = model.materials[i];
    Material mat;
    mat.name = gm.name.empty() ? cat("material_", i) : gm.name;
    const std::vector<double>& f = gm.pbrMetallicRoughness.baseColorFactor;
    if (f.size() == 4)
      mat.baseColor = glm::vec4(float(f[0]), float(f[1]), float(f[2]), float(f[3]));
    for (const std::string& ext : texturesOnly)
      if (mat.unsupported.empty() && usesExtension(model, gm, ext)) mat.unsupported = ext;
    const tinygltf::TextureInfo& info = gm.pbrMetallicRoughness.baseColorTexture;
    if (info.index >= 0 && size_t(info.index) < model.textures.size()) {
      if (info.texCoord != 0) {
        if (mat.unsupported.empty())
          mat.unsupported =
              cat("baseColorTexture.texCoord ", info.texCoord, " (only TEXCOORD_0 is read)");
      } else if (model.textures[size_t(info.index)].source >= 0) {
        int& t = textureOf[size_t(info.index)];
        if (t < 0) {
          const tinygltf::Texture& gt = model.textures[size_t(info.index)];
          const size_t img = size_t(gt.source);
          const tinygltf::Image& image = model.images.at(img);
          SurfaceTexture tex;
          tex.where = cat(file, ": /images/", img);
          if (!image.uri.empty() && !isDataUri(image.uri)) {
            tex.path = resolveUri(source.baseDir, image.uri);
          } else {
            tex.bytes = image.image;
            tex.mimeType = image.mimeType;
          }
          if (gt.sampler >= 0 && size_t(gt.sampler) < model.samplers.size()) {
            const tinygltf::Sampler& s = model.samplers[size_t(gt.sampler)];
            tex.wrapS = wrapOf(s.wrapS);
            tex.wrapT = wrapOf(s.wrapT);
            tex.nearest = s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
          }
          t = int(scene.textures.size());
          scene.textures.push_back(std::move(tex));
        }
        mat.baseColorTexture = t;
      }
    }
    scene.materialNames.push_back(mat.name);
    scene.materials.push_back(std::move(mat));
  }
  const uint32_t defaultMaterial = uint32_t(scene.materials.size());
  if (needDefault) {
    Material mat;
    mat.name = "default";
    scene.materialNames.push_back(mat.name);
    scene.materials.push_back(std::move(mat));
  }

  // Meshes.
  Builder builder{model, file, options, scene, defaultMaterial};
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    scene.meshNames.push_back(model.meshes[m].name.empty() ? cat("mesh_", m)
                                                           : model.meshes[m].name);
    scene.meshes.push_back(builder.buildMesh(m));
  }

  // Nodes: every node's name; instances and cameras of the chosen scene, depth first.
  for (size_t k = 0; k < model.nodes.size(); ++k)
    scene.instanceNames.push_back(model.nodes[k].name.empty() ? cat("node_", k)
                                                              : model.nodes[k].name);
  if (model.scenes.empty()) return scene;
  const tinygltf::Scene& s = model.scenes[size_t(sceneIndex)];
  std::vector<std::pair<int, glm::dmat4>> stack;
  for (auto it = s.nodes.rbegin(); it != s.nodes.rend(); ++it)
    stack.push_back({*it, glm::dmat4(1.0)});
  while (!stack.empty()) {
    const auto [k, parent] = stack.back();
    stack.pop_back();
    const tinygltf::Node& node = model.nodes[size_t(k)];
    const glm::dmat4 world = parent * localFromNode(node);
    if (node.mesh >= 0) scene.instances.push_back({size_t(node.mesh), world, uint32_t(k)});
    if (node.camera >= 0) {
      const tinygltf::Camera& gc = model.cameras[size_t(node.camera)];
      SceneCamera cam;
      cam.name = node.name.empty() ? cat("camera_", k) : node.name;
      cam.node = uint32_t(k);
      cam.worldFromCamera = world;
      if (gc.type == "orthographic") {
        cam.projection = SceneCamera::Projection::Orthographic;
        cam.xmag = gc.orthographic.xmag;
        cam.ymag = gc.orthographic.ymag;
        cam.znear = gc.orthographic.znear;
        cam.zfar = gc.orthographic.zfar;
      } else {
        cam.yfov = gc.perspective.yfov;
        if (gc.perspective.aspectRatio > 0) cam.aspectRatio = gc.perspective.aspectRatio;
        cam.znear = gc.perspective.znear;
        if (gc.perspective.zfar > 0) cam.zfar = gc.perspective.zfar;
      }
      scene.cameras.push_back(std::move(cam));
    }
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it)
      stack.push_back({*it, world});
  }
  return scene;
}

std::string directoryOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

}  // namespace

SceneFile loadGltfFromMemory(const char* data, size_t size, const std::string& name,
                             const LoadOptions& options) {
  Source source;
  source.file = name;
  source.baseDir = directoryOf(name);
  tinygltf::Model model = parse(data, size, source);
  return buildScene(model, source, size, options);
}

SceneFile loadGltf(const std::string& path, const LoadOptions& options) {
  const MappedFile file(path);  // mapped, not read: the file's pages are not copied twice
  return loadGltfFromMemory(file.data(), file.size(), path, options);
}

}  // namespace aperture
