#pragma once
// Camera files in: COLMAP sparse models (text or binary), transforms.json (nerfstudio and
// original NeRF / instant-ngp), OpenCV-style JSON or YAML. Camera files out: COLMAP text and
// binary models, nerfstudio transforms.json, OpenCV JSON, and the per-image sidecar JSON.
// Every reader returns the same CameraFile: sensors shared by images (a COLMAP camera used by
// many images is one sensor) and images with their world-to-camera pose in OpenCV axes.
#include <string>
#include <vector>

#include "cameras/lenses/calibration.h"

namespace aperture {

enum class CameraFileFormat {
  ColmapText,    ///< cameras.txt + images.txt in a folder
  ColmapBinary,  ///< cameras.bin + images.bin in a folder
  Nerfstudio,    ///< transforms.json with fl_x / fl_y (nerfstudio)
  InstantNgp,    ///< transforms.json with camera_angle_x only (original NeRF, instant-ngp)
  OpenCVJson,    ///< per camera K, dist, R or rvec, t, width, height
  OpenCVYaml,    ///< the same in OpenCV FileStorage YAML
};
const char* cameraFileFormatName(CameraFileFormat f);

/// One image of a camera file.
struct CalibratedImage {
  std::string name;  ///< as the file names it (COLMAP NAME, nerf file_path), subfolders kept
  int sensor = 0;    ///< index into CameraFile::sensors
  glm::dmat4 cvCameraFromWorld{1.0};  ///< OpenCV axes (x right, y down, z forward)
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
};

/// Reads PATH: a COLMAP model folder (text or binary; points3D not needed), a
/// transforms.json, or an OpenCV JSON / YAML file. Throws Error naming the file and the
/// entry (camera id, image name or line) for anything malformed: truncated binary, wrong
/// parameter count, unsupported model (named), non-rotation R, missing image size, ...
CameraFile readCameraFile(const std::string& path);

/// Writers. Each writes atomically (core/io/atomic_file.h); `dir` is created when missing.
void writeColmapText(const CameraFile& file, const std::string& dir);
void writeColmapBinary(const CameraFile& file, const std::string& dir);
void writeNerfstudioJson(const CameraFile& file, const std::string& path);
void writeOpenCVJson(const CameraFile& file, const std::string& path);

/// The sidecar JSON of one rendered image: K, the distortion model and coefficients (COLMAP
/// names and OpenCV order), the pixel convention, image size, world-to-camera in OpenCV and
/// in OpenGL axes, and camera-to-world in both.
std::string cameraSidecarJson(const CalibratedSensor& sensor, const glm::dmat4& cvCameraFromWorld);

}  // namespace aperture
