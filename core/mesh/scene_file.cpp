#include "core/mesh/scene_file.h"

#include <chrono>

#include "core/util/error.h"

namespace aperture {

bool isGltfPath(const std::string& path) {
  const std::string ext = lowerExtension(path);
  return ext == ".gltf" || ext == ".glb";
}

namespace {

/// The last path component without its extension ("bunny" for "meshes/bunny.ply").
std::string stemOf(const std::string& spec) {
  const size_t slash = spec.find_last_of('/');
  std::string name = slash == std::string::npos ? spec : spec.substr(slash + 1);
  const size_t dot = name.find_last_of('.');
  if (dot != std::string::npos && dot > 0) name.resize(dot);
  return name;
}

/// A PLY file or a procedural spec: one mesh placed once.
SceneFile singleMeshFile(const std::string& spec, const LoadOptions& options) {
  SceneFile file;
  file.path = spec;
  Mesh mesh = loadUnfinishedMesh(spec, options);
  file.fileBytes = mesh.stats.fileBytes;
  const std::string name = spec.rfind("procedural:", 0) == 0 ? spec : stemOf(spec);
  file.meshes.push_back(std::move(mesh));
  file.instances.push_back({0, glm::dmat4(1.0), 0});
  file.instanceNames = {name};
  file.meshNames = {name};
  return file;
}

}  // namespace

SceneFile loadSceneFile(const std::string& spec, const LoadOptions& options) {
  if (spec.rfind("procedural:", 0) != 0) {
    if (isGltfPath(spec)) return loadGltf(spec, options);
    if (lowerExtension(spec) == ".obj") return loadObjScene(spec, options);
  }
  return singleMeshFile(spec, options);
}

// loadGltf and loadGltfFromMemory: core/mesh/gltf.cpp. loadObjScene: core/mesh/obj.cpp.

}  // namespace aperture
