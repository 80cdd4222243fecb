#pragma once
// Inside the camera-file readers and writers: the per-format readers that readCameraFile
// dispatches to, and the few helpers several formats share (sensor sharing, pixel-centre
// shifts of a lens, the OpenCV view of a lens, JSON files and matrices).
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "core/util/error.h"

namespace aperture::camera_files {

CameraFile readColmapText(const std::string& dir);
CameraFile readColmapBinary(const std::string& dir);
/// transforms.json already parsed: nerfstudio when fl_x is given (top level or frames), else
/// original NeRF / instant-ngp (camera_angle_x).
CameraFile readNerfJson(const std::string& path, const nlohmann::json& doc);
CameraFile readOpenCVJson(const std::string& path, const nlohmann::json& doc);
CameraFile readOpenCVYaml(const std::string& path);
/// The camera nodes of a glTF scene (gltf_file.cpp).
CameraFile readGltfCameras(const std::string& path, const CameraFileOptions& options);

/// The whole file parsed as JSON; Error naming the file and the parser's message.
nlohmann::json readJsonFile(const std::string& path);

/// The index of `sensor` in file.sensors, appending it (with id "1", "2", … in order of first
/// use) when no equal sensor is there yet: readers of formats without camera ids share
/// identical sensors this way.
int shareSensor(CameraFile& file, const CalibratedSensor& sensor);

/// The same sensor with its principal point given in the `to` pixel convention (cx, cy
/// shifted by ±½; nothing else changes).
CalibratedSensor inPixelCentre(const CalibratedSensor& sensor, PixelCentre to);

/// A lens as OpenCV's camera model sees it: the standard model (dist = k1 k2 p1 p2 [k3 [k4 k5
/// k6]]) or cv::fisheye (k1 k2 k3 k4), with K = [fx 0 cx; 0 fy cy; 0 0 1]. Nothing for a
/// model OpenCV has no equal of (THIN_PRISM_FISHEYE).
struct OpenCVLens {
  bool fisheye = false;
  std::vector<double> dist;
};
std::optional<OpenCVLens> openCVLens(const Lens& lens);
/// A model's coefficients in a format's slots (LensSpelling), or nothing when a non-zero
/// coefficient has no slot there.
std::optional<std::vector<double>> slotValues(const LensSpelling& spelling,
                                              const std::vector<double>& coefficients);
/// The lens of `model` whose coefficients fill a format's slot `values` (fx, fy, cx, cy in
/// `intrinsics`), or nothing when the model cannot hold them: a non-zero value in a slot it
/// does not fill, or fx ≠ fy for a model with one focal length.
std::optional<Lens> lensOfSlots(const LensModelInfo& model, const std::vector<double>& intrinsics,
                                const LensSpelling& spelling, const std::vector<double>& values);

/// A JSON value for an error message (bytes that are not UTF-8 shown as U+FFFD: text from YAML
/// or a hostile file need not be UTF-8, and json::dump would throw on it).
std::string shown(const nlohmann::json& j);
/// The text of a JSON file to write; Error naming `path` when a string is not UTF-8 (a name
/// read from YAML).
std::string jsonFileText(const nlohmann::json& doc, const std::string& path);

/// 4×4 row-major nested list.
nlohmann::json rowMajorJson(const glm::dmat4& m);
/// A 4×4 matrix from a row-major nested list of numbers; Error naming `context` otherwise.
glm::dmat4 dmat4FromJson(const nlohmann::json& j, const std::string& context);

/// `value` as a finite double; Error naming `context` otherwise.
double finiteNumber(const nlohmann::json& value, const std::string& context);
/// `value` as an image dimension (integer in [1, kMaxImageSide]); Error naming `context`.
int imageSide(const nlohmann::json& value, const std::string& context);
/// The largest image width or height a camera file may give.
inline constexpr long long kMaxImageSide = 1 << 20;

/// Calls f(); an Error it throws is rethrown with "`context`: " in front.
template <typename F>
auto withContext(const std::string& context, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const Error& e) {
    throw Error(context + ": " + e.what());
  }
}

}  // namespace aperture::camera_files
