// libFuzzer target: the OBJ loader and finishMesh on arbitrary bytes, then the OBJ scene loader
// (objects, materials, texture coordinates and normals asked for) on the same bytes. The name
// sits in a directory that does not exist, so an mtllib with a relative path is a missing
// library (an Error) rather than a file of the fuzzer's working directory.
#include <cstddef>
#include <cstdint>

#include "core/mesh/mesh.h"
#include "core/mesh/scene_file.h"
#include "core/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const char* text = reinterpret_cast<const char*>(data);
  try {
    aperture::Mesh mesh = aperture::loadObjFromMemory(text, size, "fuzz.obj");
    aperture::finishMesh(mesh, {});
  } catch (const aperture::Error&) {
    // A clear error is the right answer to a malformed file.
  }
  try {
    aperture::LoadOptions all;
    all.vertexNormals = all.texcoords = all.groups = all.materials = true;
    aperture::SceneFile scene =
        aperture::loadObjSceneFromMemory(text, size, "/nonexistent-aperture-fuzz/fuzz.obj", all);
    aperture::finishMesh(scene.meshes.at(0), all);
  } catch (const aperture::Error&) {
  }
  return 0;
}
