// libFuzzer target: the PLY loader and finishMesh on arbitrary bytes.
#include <cstddef>
#include <cstdint>

#include "core/error.h"
#include "core/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    aperture::Mesh mesh =
        aperture::loadPlyFromMemory(reinterpret_cast<const char*>(data), size, "fuzz.ply");
    aperture::finishMesh(mesh, {});
  } catch (const aperture::Error&) {
    // A clear error is the right answer to a malformed file.
  }
  return 0;
}
