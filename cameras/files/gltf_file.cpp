// The camera nodes of a glTF 2.0 scene as a camera file. The glTF loader (core/mesh/scene_file.h)
// reads the file and places each camera by its node's world transform; here the cameras become
// images named by their nodes, posed through gltfCvCameraFromWorld, the one owner of glTF's
// camera axes. Their projection (yfov, aspectRatio, xmag, ymag, znear, zfar) stays as the file
// gives it: the image size is the caller's, so the camera parameters are made later
// (gltfCameraParams, apps/services/camera_file_params.h).
#include <cmath>
#include <map>

#include "cameras/files/camera_file.h"
#include "cameras/files/camera_file_formats.h"

namespace aperture {

glm::dmat4 gltfCvCameraFromWorld(const glm::dmat4& worldFromCamera, const std::string& context) {
  glm::dmat4 rigid = worldFromCamera;
  for (int axis = 0; axis < 3; ++axis) {
    const glm::dvec3 column(worldFromCamera[axis]);
    const double length = glm::length(column);
    if (!(length > 0) || !std::isfinite(length))
      throw Error(cat(context, ": the node's world transform has a zero or non-finite ",
                      "xyz"[axis], " axis (scale ", length, ")"));
    rigid[axis] = glm::dvec4(column / length, 0.0);
  }
  // glTF's camera axes are OpenGL's: x right, y up, looking down −z.
  return cvCameraFromWorldOf(rigid, AxisConvention::OpenGL, true, context);
}

namespace camera_files {

CameraFile readGltfCameras(const std::string& path, const CameraFileOptions& options) {
  LoadOptions load;
  load.gltfScene = options.gltfScene;
  const SceneFile scene = loadGltf(path, load);
  if (scene.cameras.empty())
    throw Error(cat(path, ": the glTF scene", options.gltfScene ? cat(" ", *options.gltfScene) : "",
                    " has no camera node (a node with \"camera\")"));
  CameraFile file;
  file.path = path;
  file.format = CameraFileFormat::Gltf;
  file.gltfCameras = scene.cameras;
  // Two camera nodes of one name would be one image (and one output file): each of them gets
  // its node index appended.
  std::map<std::string, int> uses;
  for (const SceneCamera& c : scene.cameras) ++uses[c.name];
  for (size_t k = 0; k < scene.cameras.size(); ++k) {
    const SceneCamera& c = scene.cameras[k];
    CalibratedImage image;
    image.name = uses[c.name] > 1 ? cat(c.name, "_", c.node) : c.name;
    image.sensor = -1;
    image.gltfCamera = int(k);
    image.cvCameraFromWorld = gltfCvCameraFromWorld(
        c.worldFromCamera, cat(path, ": camera '", c.name, "' (/nodes/", c.node, ")"));
    file.images.push_back(std::move(image));
  }
  return file;
}

}  // namespace camera_files

}  // namespace aperture
