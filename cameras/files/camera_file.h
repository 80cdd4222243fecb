#pragma once
// Camera files in: COLMAP sparse models (text or binary), transforms.json (nerfstudio and
// original NeRF / instant-ngp), OpenCV-style JSON or YAML, and the camera nodes of a glTF 2.0
// scene (.gltf, .glb). Camera files out: COLMAP text and binary models, nerfstudio
// transforms.json, OpenCV JSON, and the per-image sidecar JSON.
// Every reader returns the same CameraFile: sensors shared by images (a COLMAP camera used by
// many images is one sensor) and images with their world-to-camera pose in OpenCV axes. A glTF
// camera has no sensor (its image size is the caller's, and an orthographic one has no lens):
// its image keeps the file's projection (CameraFile::gltfCameras).
#include <optional>
#include <string>
#include <vector>

#include "cameras/lenses/calibration.h"
#include "core/mesh/scene_file.h"

namespace aperture {

enum class CameraFileFormat {
  ColmapText,    ///< cameras.txt + images.txt in a folder
  ColmapBinary,  ///< cameras.bin + images.bin in a folder
  Nerfstudio,    ///< transforms.json with fl_x / fl_y (nerfstudio)
  InstantNgp,    ///< transforms.json with camera_angle_x only (original NeRF, instant-ngp)
  OpenCVJson,    ///< per camera K, dist, R or rvec, t, width, height
  OpenCVYaml,    ///< the same in OpenCV FileStorage YAML
  Gltf,          ///< the camera nodes of a glTF 2.0 scene (.gltf, .glb)
};
const char* cameraFileFormatName(CameraFileFormat f);

/// One image of a camera file.
struct CalibratedImage {
  std::string name;  ///< as the file names it (COLMAP NAME, nerf file_path), subfolders kept
  int sensor = 0;    ///< index into CameraFile::sensors; -1 for a glTF camera
  glm::dmat4 cvCameraFromWorld{1.0};  ///< OpenCV axes (x right, y down, z forward)
  int gltfCamera = -1;  ///< index into CameraFile::gltfCameras; -1 for a calibrated image
};

struct CameraFile {
  std::string path;
  CameraFileFormat format = CameraFileFormat::ColmapText;
  std::vector<CalibratedSensor> sensors;
  std::vector<std::string> sensorIds;  ///< the file's id of each sensor (COLMAP CAMERA_ID)
  /// The file's id of each image (COLMAP IMAGE_ID), parallel to `images`; empty when the
  /// format has none. COLMAP tracks (cameras/files/points_file.h) refer to images by it.
  std::vector<std::string> imageIds;
  std::vector<CalibratedImage> images;
  /// glTF: the camera of each image, as the file gives it (projection and node pose).
  std::vector<SceneCamera> gltfCameras;
};

/// What reading a camera file may need beyond its path.
struct CameraFileOptions {
  /// glTF: the scene whose camera nodes to read (--gltf-scene); unset: the file's `scene`.
  std::optional<int> gltfScene;
};

/// Reads PATH: a COLMAP model folder (text or binary; points3D not needed), a
/// transforms.json, an OpenCV JSON / YAML file or a glTF scene (.gltf, .glb: its camera nodes,
/// named by their nodes). Throws Error naming the file and the entry (camera id, image name or
/// line) for anything malformed: truncated binary, wrong parameter count, unsupported model
/// (named), non-rotation R, missing image size, a glTF scene without cameras, ...
CameraFile readCameraFile(const std::string& path, const CameraFileOptions& options = {});

/// The one owner of glTF's camera axes (glTF 2.0, 3.10: the camera looks down its node's −Z
/// with +Y up and +X right, OpenGL's axes): the world-to-camera pose, in OpenCV axes, of a
/// camera placed by `worldFromCamera` (its node's world transform). Scale in the node
/// transforms is removed (each axis normalised); a transform whose axes are then not a
/// rotation (shear, a mirror) or not finite is an Error naming `context`. The lecture frame of
/// the result has W = the node's +Z axis, V its +Y axis and e its origin.
glm::dmat4 gltfCvCameraFromWorld(const glm::dmat4& worldFromCamera, const std::string& context);

/// Writers. Each writes atomically (core/io/atomic_file.h); `dir` is created when missing. A
/// file with glTF cameras (no sensor) is refused.
void writeColmapText(const CameraFile& file, const std::string& dir);
void writeColmapBinary(const CameraFile& file, const std::string& dir);
void writeNerfstudioJson(const CameraFile& file, const std::string& path);
void writeOpenCVJson(const CameraFile& file, const std::string& path);

/// The sidecar JSON of one rendered image: K, the distortion model and coefficients (COLMAP
/// names and OpenCV order), the pixel convention, image size, world-to-camera in OpenCV and
/// in OpenGL axes, and camera-to-world in both.
std::string cameraSidecarJson(const CalibratedSensor& sensor, const glm::dmat4& cvCameraFromWorld);

}  // namespace aperture
