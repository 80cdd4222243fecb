#pragma once
// Internal to the glTF 2.0 loader (gltf*.cpp), not for other parts: the pieces the loader is
// split into. gltf.cpp reads the file (tinygltf) and builds the SceneFile (nodes, meshes,
// materials, cameras); gltf_checks.cpp validates the JSON before tinygltf sees it;
// gltf_accessors.cpp reads accessors; gltf_compression.cpp decodes Draco primitives and
// meshopt buffer views. Every error is "<file>: <JSON pointer>: <what>".
// tinygltf parses, OpenImageIO (core/io) decodes images later: the image bytes and URIs are
// kept, nothing is decoded (every file that includes tiny_gltf.h must see these settings).
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
// libdraco.so carries its own tinygltf (built with other settings) and exports its symbols,
// which took the place of ours at link time: ours lives in a namespace of its own.
#define tinygltf aperture_tinygltf
#include <tiny_gltf.h>

#include <cstddef>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "core/util/huge_pages.h"

namespace aperture::gltf {

/// Throws Error("<file>: <pointer>: <what>"); an empty pointer (the whole document) is left out.
[[noreturn]] void fail(const std::string& file, const std::string& pointer,
                       const std::string& what);

/// The file an external `uri` names: percent-decoded, relative to `baseDir`.
std::string resolveUri(const std::string& baseDir, const std::string& uri);
/// True for "data:" URIs.
bool isDataUri(const std::string& uri);

/// What the checks know of the file besides its JSON.
struct Source {
  std::string file;          ///< names the file in messages
  std::string baseDir;       ///< external URIs resolve here ("" or ending in '/')
  bool glb = false;          ///< a binary container
  size_t binChunkBytes = 0;  ///< the GLB's BIN chunk (0: none)
};

/// What checkDocument found that the loader must change before tinygltf reads the JSON.
struct Rewrites {
  /// Buffers of EXT_meshopt_compression that are fallbacks without data (no uri): tinygltf
  /// would reject them, so they become one-byte data URIs (the loader never reads them).
  std::vector<size_t> emptyFallbackBuffers;
  /// (mesh, primitive) of KHR_draco_mesh_compression primitives: their `indices` accessor
  /// has no buffer view (the indices are in the Draco data), which tinygltf rejects, so the
  /// loader drops `indices` from them.
  std::vector<std::pair<size_t, size_t>> dracoPrimitives;
};

/// Validates the JSON document before tinygltf parses it: types and ranges of every index
/// (scene, nodes, meshes, accessors, buffer views, buffers, materials, textures, images,
/// samplers, cameras), buffers (external file present and long enough, data URIs in base64,
/// GLB chunk long enough), buffer views inside their buffers, images present, and the node
/// graph (no cycle, no node with two parents). Throws Error with the pointer.
Rewrites checkDocument(const nlohmann::json& doc, const Source& source);

/// Bytes `accessor` spans in its buffer view, checked against the loaded buffer.
struct ViewBytes {
  const unsigned char* data = nullptr;
  size_t size = 0;
};
ViewBytes viewBytes(const tinygltf::Model& model, int view, const std::string& file,
                    const std::string& pointer);

/// Reads accessor `index` as floats, `components` per element (its type's count).
/// Normalized integers go through the glTF formulas (c / 255, max(c / 127, -1), ...); other
/// integers (KHR_mesh_quantization) keep their value, unless `normalizeIntegers` (colours).
/// Sparse accessors are applied over their base view or zeros.
LargeBuffer<float> readFloats(const tinygltf::Model& model, int index, const std::string& file,
                              int& components, bool normalizeIntegers = false);
/// Reads accessor `index` as vertex indices (SCALAR unsigned byte, short or int).
LargeBuffer<uint32_t> readIndices(const tinygltf::Model& model, int index, const std::string& file);

/// Replaces every EXT_meshopt_compression buffer view by its decoded bytes (a new buffer
/// appended to model.buffers), so that accessors read them as any other view.
void decodeMeshoptViews(tinygltf::Model& model, const std::string& file);

/// The vertex data of one primitive, as the mesh builder takes it.
struct PrimitiveData {
  size_t vertexCount = 0;
  // LargeBuffers, as the mesh's own: a primitive's positions and indices become the mesh's
  // when it has only one, and large ones are read without a zero-fill first.
  LargeBuffer<float> positions;   ///< 3 per vertex
  LargeBuffer<float> normals;     ///< 3 per vertex or empty
  LargeBuffer<float> texcoords;   ///< 2 per vertex or empty
  LargeBuffer<float> colors;      ///< 4 per vertex (linear RGBA) or empty
  LargeBuffer<uint32_t> indices;  ///< empty: not indexed
  bool indexed = false;
};
/// Decodes a KHR_draco_mesh_compression primitive (`pointer` names it). Reads only the
/// attributes asked for (normals, texcoords, colors).
PrimitiveData decodeDraco(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                          const std::string& file, const std::string& pointer, bool normals,
                          bool texcoords, bool colors);

/// Expands 3- or 4-component colours to linear RGBA (A = 1 for RGB).
LargeBuffer<float> rgba(const LargeBuffer<float>& values, int components);

}  // namespace aperture::gltf
