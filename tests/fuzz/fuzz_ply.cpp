// libFuzzer target: the PLY loader and finishMesh on arbitrary bytes, both as the renderer
// loads positions only and with the mesh data AOVs ask for (integer face and vertex
// properties, vertex normals), which take the general reader.
#include <cstddef>
#include <cstdint>

#include "core/error.h"
#include "core/mesh.h"

namespace {

void loadAndFinish(const uint8_t* data, size_t size, const aperture::LoadOptions& options) {
  try {
    aperture::Mesh mesh =
        aperture::loadPlyFromMemory(reinterpret_cast<const char*>(data), size, "fuzz.ply", options);
    aperture::finishMesh(mesh, options);
  } catch (const aperture::Error&) {
    // A clear error is the right answer to a malformed file.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  loadAndFinish(data, size, {});
  aperture::LoadOptions withData;
  withData.vertexNormals = true;
  withData.properties = {{aperture::PropertyDomain::Face, "object_id"},
                         {aperture::PropertyDomain::Vertex, "label"}};
  loadAndFinish(data, size, withData);
  return 0;
}
