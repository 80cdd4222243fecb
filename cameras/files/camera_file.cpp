// Camera files: which format a path holds, the helpers the formats share, and the sidecar JSON
// of a rendered image. The formats themselves live in colmap_file.cpp, nerf_file.cpp and
// opencv_file.cpp.
#include "cameras/files/camera_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cameras/files/camera_file_formats.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

namespace fs = std::filesystem;
using nlohmann::json;

namespace camera_files {

json readJsonFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat(path, ": cannot open the file"));
  std::ostringstream text;
  text << in.rdbuf();
  try {
    return json::parse(text.str());
  } catch (const json::exception& e) {
    throw Error(cat(path, ": not valid JSON (", e.what(), ")"));
  }
}

std::string shown(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

std::string jsonFileText(const json& doc, const std::string& path) {
  try {
    return doc.dump(2) + "\n";
  } catch (const json::exception& e) {
    throw Error(cat(path, ": cannot be written as JSON (", e.what(), ")"));
  }
}

int shareSensor(CameraFile& file, const CalibratedSensor& sensor) {
  for (size_t i = 0; i < file.sensors.size(); ++i)
    if (file.sensors[i] == sensor) return int(i);
  file.sensors.push_back(sensor);
  file.sensorIds.push_back(std::to_string(file.sensors.size()));
  return int(file.sensors.size() - 1);
}

CalibratedSensor inPixelCentre(const CalibratedSensor& sensor, PixelCentre to) {
  if (sensor.pixelCentre == to) return sensor;
  if (sensor.lens.info().ownMap())
    throw Error(cat("camera model ", sensor.lens.info().name, " has no principal point to give in ",
                    pixelCentreName(to), " pixel centres"));
  // The raster position of the principal point is the same in both conventions.
  const glm::dvec2 raster =
      rasterOfSourcePixel({sensor.lens.cx(), sensor.lens.cy()}, sensor.pixelCentre);
  const glm::dvec2 shifted = sourcePixelOfRaster(raster, to);
  std::vector<double> params = sensor.lens.params();
  const size_t cxIndex = sensor.lens.info().singleFocal() ? 1 : 2;
  params[cxIndex] = shifted.x;
  params[cxIndex + 1] = shifted.y;
  CalibratedSensor out = sensor;
  out.lens = Lens(sensor.lens.model(), params);
  out.pixelCentre = to;
  return out;
}

// The model's OpenCV spelling (LensModelInfo::opencv): each slot filled from its coefficient;
// nothing when the model has none or a non-zero coefficient has no slot.
std::optional<OpenCVLens> openCVLens(const Lens& lens) {
  const LensSpelling& spelling = lens.info().opencv;
  if (!spelling.expressible()) return std::nullopt;
  const std::optional<std::vector<double>> dist = slotValues(spelling, lens.distortion());
  if (!dist) return std::nullopt;
  return OpenCVLens{std::string(spelling.name) == "fisheye", *dist};
}

std::optional<std::vector<double>> slotValues(const LensSpelling& spelling,
                                              const std::vector<double>& coefficients) {
  std::vector<double> values(spelling.slots.size(), 0.0);
  std::vector<bool> used(coefficients.size(), false);
  for (size_t i = 0; i < spelling.slots.size(); ++i)
    if (spelling.slots[i] >= 0) {
      values[i] = coefficients.at(size_t(spelling.slots[i]));
      used[size_t(spelling.slots[i])] = true;
    }
  for (size_t j = 0; j < coefficients.size(); ++j)
    if (!used[j] && coefficients[j] != 0) return std::nullopt;
  return values;
}

std::optional<Lens> lensOfSlots(const LensModelInfo& model, const std::vector<double>& intrinsics,
                                const LensSpelling& spelling, const std::vector<double>& values) {
  std::vector<double> params;
  if (model.singleFocal()) {
    if (intrinsics[0] != intrinsics[1]) return std::nullopt;
    params = {intrinsics[0], intrinsics[2], intrinsics[3]};
  } else {
    params = intrinsics;
  }
  params.resize(model.paramNames.size(), 0.0);
  for (size_t i = 0; i < values.size(); ++i) {
    if (values[i] == 0) continue;
    if (i >= spelling.slots.size() || spelling.slots[i] < 0) return std::nullopt;
    params[model.intrinsicCount() + size_t(spelling.slots[i])] = values[i];
  }
  return Lens(model.id, params);
}

json rowMajorJson(const glm::dmat4& m) {
  json rows = json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({m[0][r], m[1][r], m[2][r], m[3][r]});
  return rows;
}

glm::dmat4 dmat4FromJson(const json& j, const std::string& context) {
  if (!j.is_array() || j.size() != 4)
    throw Error(cat(context, ": expected a 4×4 matrix as a list of 4 rows, got ", shown(j)));
  glm::dmat4 m(1.0);
  for (int r = 0; r < 4; ++r) {
    if (!j[r].is_array() || j[r].size() != 4)
      throw Error(cat(context, ": row ", r, " of the 4×4 matrix is ", shown(j[r]),
                      " (expected 4 numbers)"));
    for (int c = 0; c < 4; ++c)
      m[c][r] = finiteNumber(j[r][c], cat(context, " row ", r, " column ", c));
  }
  return m;
}

double finiteNumber(const json& value, const std::string& context) {
  if (!value.is_number()) throw Error(cat(context, ": expected a number, got ", shown(value)));
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw Error(cat(context, ": ", v, " is not finite"));
  return v;
}

int imageSide(const json& value, const std::string& context) {
  const double v = finiteNumber(value, context);
  if (v != std::floor(v) || v < 1 || v > double(kMaxImageSide))
    throw Error(cat(context, ": image size ", shown(value), " must be an integer in [1, ",
                    kMaxImageSide, "]"));
  return int(v);
}

}  // namespace camera_files

const char* cameraFileFormatName(CameraFileFormat f) {
  switch (f) {
    case CameraFileFormat::ColmapText:
      return "COLMAP text";
    case CameraFileFormat::ColmapBinary:
      return "COLMAP binary";
    case CameraFileFormat::Nerfstudio:
      return "nerfstudio transforms.json";
    case CameraFileFormat::InstantNgp:
      return "NeRF / instant-ngp transforms.json";
    case CameraFileFormat::OpenCVJson:
      return "OpenCV JSON";
    case CameraFileFormat::OpenCVYaml:
      return "OpenCV YAML";
    case CameraFileFormat::Gltf:
      return "glTF cameras";
  }
  return "unknown";
}

namespace {

// A COLMAP model folder: binary wins when both are there, as in COLMAP's own reader.
CameraFile readColmapFolder(const std::string& dir) {
  const auto has = [&](const char* name) {
    std::error_code ec;
    return fs::is_regular_file(fs::path(dir) / name, ec);
  };
  if (has("cameras.bin") && has("images.bin")) return camera_files::readColmapBinary(dir);
  if (has("cameras.txt") && has("images.txt")) return camera_files::readColmapText(dir);
  throw Error(cat(dir,
                  ": a camera folder needs COLMAP's cameras.txt and images.txt (text model) "
                  "or cameras.bin and images.bin (binary model)"));
}

}  // namespace

CameraFile readCameraFile(const std::string& path, const CameraFileOptions& options) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return readColmapFolder(path);
  if (!fs::exists(path, ec)) throw Error(cat(path, ": no such file or folder"));
  const fs::path p(path);
  const std::string name = p.filename().string();
  // A COLMAP model file stands for its folder.
  for (const char* colmapName : {"cameras.txt", "images.txt", "cameras.bin", "images.bin"})
    if (name == colmapName)
      return readColmapFolder(p.parent_path().empty() ? "." : p.parent_path().string());
  const std::string ext = toLowerAscii(p.extension().string());
  if (ext == ".yaml" || ext == ".yml") return camera_files::readOpenCVYaml(path);
  if (isGltfPath(path)) return camera_files::readGltfCameras(path, options);
  if (ext == ".json") {
    const json doc = camera_files::readJsonFile(path);
    if (doc.is_object() && doc.contains("frames")) return camera_files::readNerfJson(path, doc);
    return camera_files::readOpenCVJson(path, doc);
  }
  throw Error(cat(path,
                  ": unknown camera file (expected a COLMAP model folder, a transforms.json, "
                  "an OpenCV .json or an OpenCV .yaml / .yml, or a glTF .gltf / .glb)"));
}

// The sidecar is JSON written by nlohmann::json, whose numbers print in the shortest form that
// reads back to the same double (at most 17 significant digits): every value is exact.
std::string cameraSidecarJson(const CalibratedSensor& sensor, const glm::dmat4& cvCameraFromWorld) {
  const Lens& lens = sensor.lens;
  json j;
  j["width"] = sensor.width;
  j["height"] = sensor.height;
  j["pixel_centre"] = pixelCentreName(sensor.pixelCentre);
  j["K"] = {{lens.fx(), 0.0, lens.cx()}, {0.0, lens.fy(), lens.cy()}, {0.0, 0.0, 1.0}};
  j["model"] = lens.info().name;
  j["param_names"] = lens.info().paramNames;
  j["params"] = lens.params();
  if (const auto cv = camera_files::openCVLens(lens))
    j[cv->fisheye ? "distortion_opencv_fisheye" : "distortion_opencv"] = cv->dist;
  j["world_to_camera_opencv"] = camera_files::rowMajorJson(cvCameraFromWorld);
  j["world_to_camera_opengl"] = camera_files::rowMajorJson(
      poseInConvention(cvCameraFromWorld, AxisConvention::OpenGL, false));
  j["camera_to_world_opencv"] =
      camera_files::rowMajorJson(poseInConvention(cvCameraFromWorld, AxisConvention::OpenCV, true));
  j["camera_to_world_opengl"] =
      camera_files::rowMajorJson(poseInConvention(cvCameraFromWorld, AxisConvention::OpenGL, true));
  return camera_files::jsonFileText(j, "the sidecar JSON");
}

}  // namespace aperture
