// libFuzzer target: the glTF loader (tinygltf, the checks, accessors, Draco and meshopt
// decoding) and finishMesh on arbitrary bytes, as .gltf text or a .glb container.
#include <cstddef>
#include <cstdint>

#include "core/mesh/scene_file.h"
#include "core/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  aperture::LoadOptions options;
  options.vertexNormals = options.texcoords = options.vertexColors = options.materials = true;
  try {
    // External URIs resolve in a directory that does not exist.
    aperture::SceneFile file = aperture::loadGltfFromMemory(
        reinterpret_cast<const char*>(data), size, "/nonexistent-aperture-fuzz/fuzz.gltf", options);
    for (aperture::Mesh& mesh : file.meshes) aperture::finishMesh(mesh, {});
  } catch (const aperture::Error&) {
    // A clear error is the right answer to a malformed file.
  }
  return 0;
}
