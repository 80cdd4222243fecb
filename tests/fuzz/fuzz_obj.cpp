// libFuzzer target: the OBJ loader and finishMesh on arbitrary bytes.
#include <cstddef>
#include <cstdint>

#include "core/mesh/mesh.h"
#include "core/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    aperture::Mesh mesh =
        aperture::loadObjFromMemory(reinterpret_cast<const char*>(data), size, "fuzz.obj");
    aperture::finishMesh(mesh, {});
  } catch (const aperture::Error&) {
    // A clear error is the right answer to a malformed file.
  }
  return 0;
}
