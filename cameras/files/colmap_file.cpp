// COLMAP sparse models, text and binary (the formats of COLMAP's
// src/colmap/scene/reconstruction_io_text.cc and reconstruction_io_binary.cc):
//
//   cameras.txt  one line per camera: CAMERA_ID MODEL WIDTH HEIGHT PARAMS[] (model by name,
//                parameters in the order of cameras/lenses/lens_model.h); '#' starts a comment
//                line.
//   images.txt   two lines per image: IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then the
//                2D points (X Y POINT3D_ID triples; may be empty), which are skipped here.
//   cameras.bin  uint64 count; per camera uint32 id, int32 model id, uint64 width, uint64
//                height, the parameters as float64.
//   images.bin   uint64 count; per image uint32 id, float64 qw qx qy qz tx ty tz, uint32
//                camera id, the name NUL-terminated, uint64 point count, and per point float64
//                x, y and uint64 point3D id (24 bytes, skipped here).
// Everything is little-endian. (q, t) is world-to-camera, x_cam = R(q)·x_world + t, with q a
// Hamilton quaternion, w first, in OpenCV camera axes. Pixel centres are half-integer.
//
// Writers give text with 17 significant digits (every double reads back bit-exact) and an
// empty points3D file beside the two others, so that COLMAP itself opens the folder. Camera
// ids come from CameraFile::sensorIds when they are distinct COLMAP ids, else 1, 2, …; image
// ids are 1, 2, … in file order.
//
// A pose goes through a quaternion: R → q → R' is exact to rounding only (R' may differ from
// R in the last bits), but q itself round-trips exactly, so the text and binary files written
// from one CameraFile read back to identical CameraFiles, and a file read, written and read
// again gives back its own quaternions.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "cameras/files/camera_file_formats.h"
#include "cameras/files/colmap_reading.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"
#include "core/util/little_endian.h"
#include "core/util/mapped_file.h"

namespace aperture::camera_files {

namespace fs = std::filesystem;

namespace {

// Norm of a quaternion that is normalised rather than refused.
constexpr double kQuaternionTolerance = 1e-6;

struct ColmapCamera {
  uint32_t id = 0;
  CalibratedSensor sensor;
  std::string context;  ///< "cameras.txt line 4 (camera 2)"
};

struct ColmapImage {
  uint32_t id = 0;
  std::array<double, 4> q{};  ///< w x y z
  glm::dvec3 t{0.0};
  uint32_t cameraId = 0;
  std::string name;
  std::string context;  ///< "images.txt line 7 (image 3)"
};

// ---- rotations ----

double& at(glm::dmat3& m, int row, int col) { return m[col][row]; }
double at(const glm::dmat3& m, int row, int col) { return m[col][row]; }

// R of a unit Hamilton quaternion (w, x, y, z): R·v = q v q*.
glm::dmat3 rotationOfQuaternion(const std::array<double, 4>& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  glm::dmat3 r;
  at(r, 0, 0) = 1 - 2 * (y * y + z * z);
  at(r, 0, 1) = 2 * (x * y - w * z);
  at(r, 0, 2) = 2 * (x * z + w * y);
  at(r, 1, 0) = 2 * (x * y + w * z);
  at(r, 1, 1) = 1 - 2 * (x * x + z * z);
  at(r, 1, 2) = 2 * (y * z - w * x);
  at(r, 2, 0) = 2 * (x * z - w * y);
  at(r, 2, 1) = 2 * (y * z + w * x);
  at(r, 2, 2) = 1 - 2 * (x * x + y * y);
  return r;
}

// The unit quaternion of a rotation, w >= 0. The component with the largest magnitude is
// found from the diagonal first, so no square root of a small number is taken.
std::array<double, 4> quaternionOfRotation(const glm::dmat3& r) {
  const double m00 = at(r, 0, 0), m11 = at(r, 1, 1), m22 = at(r, 2, 2);
  const double trace = m00 + m11 + m22;
  std::array<double, 4> q{};
  if (trace >= m00 && trace >= m11 && trace >= m22) {
    const double s = 2 * std::sqrt(1 + trace);  // 4w
    q = {s / 4, (at(r, 2, 1) - at(r, 1, 2)) / s, (at(r, 0, 2) - at(r, 2, 0)) / s,
         (at(r, 1, 0) - at(r, 0, 1)) / s};
  } else if (m00 >= m11 && m00 >= m22) {
    const double s = 2 * std::sqrt(1 + m00 - m11 - m22);  // 4x
    q = {(at(r, 2, 1) - at(r, 1, 2)) / s, s / 4, (at(r, 0, 1) + at(r, 1, 0)) / s,
         (at(r, 0, 2) + at(r, 2, 0)) / s};
  } else if (m11 >= m22) {
    const double s = 2 * std::sqrt(1 - m00 + m11 - m22);  // 4y
    q = {(at(r, 0, 2) - at(r, 2, 0)) / s, (at(r, 0, 1) + at(r, 1, 0)) / s, s / 4,
         (at(r, 1, 2) + at(r, 2, 1)) / s};
  } else {
    const double s = 2 * std::sqrt(1 - m00 - m11 + m22);  // 4z
    q = {(at(r, 1, 0) - at(r, 0, 1)) / s, (at(r, 0, 2) + at(r, 2, 0)) / s,
         (at(r, 1, 2) + at(r, 2, 1)) / s, s / 4};
  }
  const double sign = q[0] < 0 ? -1.0 : 1.0;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& c : q) c = sign * c / norm;
  return q;
}

// The unit quaternion, normalised when its norm is within kQuaternionTolerance of 1.
std::array<double, 4> unitQuaternion(std::array<double, 4> q, const std::string& context) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(std::abs(norm - 1) <= kQuaternionTolerance))
    throw Error(cat(context, ": quaternion (", q[0], ", ", q[1], ", ", q[2], ", ", q[3],
                    ") has norm ", norm, " (expected a unit quaternion, within ",
                    kQuaternionTolerance, ")"));
  if (norm != 1)
    for (double& c : q) c /= norm;
  return q;
}

// ---- from parsed entries to a CameraFile ----

CameraFile assemble(const std::string& dir, CameraFileFormat format,
                    const std::vector<ColmapCamera>& cameras,
                    const std::vector<ColmapImage>& images) {
  CameraFile file;
  file.path = dir;
  file.format = format;
  std::map<uint32_t, int> sensorOfCamera;
  for (const ColmapCamera& c : cameras) {
    if (!sensorOfCamera.emplace(c.id, int(file.sensors.size())).second)
      throw Error(cat(c.context, ": camera id ", c.id, " is given twice"));
    file.sensors.push_back(c.sensor);
    file.sensorIds.push_back(std::to_string(c.id));
  }
  std::set<uint32_t> imageIds;
  std::map<std::string, std::string> contextOfName;
  for (const ColmapImage& im : images) {
    if (!imageIds.insert(im.id).second)
      throw Error(cat(im.context, ": image id ", im.id, " is given twice"));
    const auto [it, fresh] = contextOfName.emplace(im.name, im.context);
    if (!fresh)
      throw Error(
          cat(im.context, ": image name '", im.name, "' is given twice (also ", it->second, ")"));
    const auto sensor = sensorOfCamera.find(im.cameraId);
    if (sensor == sensorOfCamera.end())
      throw Error(cat(im.context, ": image '", im.name, "' refers to camera ", im.cameraId,
                      ", which the cameras file does not define"));
    glm::dmat4 pose(rotationOfQuaternion(unitQuaternion(im.q, im.context)));
    pose[3] = glm::dvec4(im.t, 1.0);
    file.images.push_back({im.name, sensor->second,
                           worldToCameraOpenCV(pose, AxisConvention::OpenCV, false, im.context)});
    file.imageIds.push_back(std::to_string(im.id));
  }
  return file;
}

CalibratedSensor colmapSensor(LensModelId model, long long width, long long height,
                              std::vector<double> params, const std::string& context) {
  if (width < 1 || width > kMaxImageSide || height < 1 || height > kMaxImageSide)
    throw Error(cat(context, ": image size ", width, " × ", height, " (each must be in [1, ",
                    kMaxImageSide, "])"));
  return withContext(context, [&] {
    return CalibratedSensor{int(width), int(height), Lens(model, std::move(params)),
                            PixelCentre::HalfInteger};
  });
}

// ---- text ----

std::vector<ColmapCamera> readCamerasText(const std::string& path) {
  std::vector<ColmapCamera> cameras;
  for (const auto& [number, line] : textLines(readWholeFile(path))) {
    if (!isDataLine(line)) continue;
    const std::vector<std::string> tok = tokensOf(line);
    std::string context = cat(path, " line ", number);
    if (tok.size() < 4)
      throw Error(
          cat(context, ": expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[], got '", line, "'"));
    ColmapCamera c;
    c.id = uint32_t(integerToken(tok[0], context, "CAMERA_ID", 0, kMaxColmapId));
    context += cat(" (camera ", c.id, ")");
    const LensModelInfo& model =
        withContext(context, [&]() -> const LensModelInfo& { return findLensModel(tok[1]); });
    const long long width = integerToken(tok[2], context, "WIDTH", 1, kMaxImageSide);
    const long long height = integerToken(tok[3], context, "HEIGHT", 1, kMaxImageSide);
    std::vector<double> params;
    for (size_t k = 4; k < tok.size(); ++k)
      params.push_back(numberToken(tok[k], context, "parameter"));
    c.sensor = colmapSensor(model.id, width, height, std::move(params), context);
    c.context = context;
    cameras.push_back(std::move(c));
  }
  return cameras;
}

std::vector<ColmapImage> readImagesText(const std::string& path) {
  std::vector<ColmapImage> images;
  const auto lines = textLines(readWholeFile(path));
  for (size_t k = 0; k < lines.size(); ++k) {
    const auto& [number, line] = lines[k];
    if (!isDataLine(line)) continue;
    std::string context = cat(path, " line ", number);
    const std::vector<std::string> tok = tokensOf(line);
    if (tok.size() < 10)
      throw Error(cat(context, ": expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, got '",
                      line, "'"));
    ColmapImage im;
    im.id = uint32_t(integerToken(tok[0], context, "IMAGE_ID", 0, kMaxColmapId));
    context += cat(" (image ", im.id, ")");
    const char* names[] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
    for (int i = 0; i < 4; ++i) im.q[i] = numberToken(tok[1 + i], context, names[i]);
    for (int i = 0; i < 3; ++i) im.t[i] = numberToken(tok[5 + i], context, names[4 + i]);
    im.cameraId = uint32_t(integerToken(tok[8], context, "CAMERA_ID", 0, kMaxColmapId));
    // The name is the rest of the line (COLMAP's names hold no spaces; ours may).
    im.name = afterTokens(line, 9);
    im.context = context;
    images.push_back(std::move(im));
    ++k;  // the 2D points line, whatever it holds (it may be empty or absent at the end)
  }
  return images;
}

// ---- binary ----

std::vector<ColmapCamera> readCamerasBinary(const std::string& path) {
  BinaryReader in(path);
  // id, model, width, height and at least as many parameters as the model with fewest.
  size_t fewest = SIZE_MAX;
  for (const LensModelInfo& m : lensModels()) fewest = std::min(fewest, m.paramNames.size());
  const uint64_t count = in.readCount(4 + 4 + 8 + 8 + fewest * 8, "the number of cameras");
  std::vector<ColmapCamera> cameras;
  for (uint64_t k = 0; k < count; ++k) {
    ColmapCamera c;
    const std::string entry = cat("camera #", k + 1);
    c.id = in.read<uint32_t>(cat("the id of ", entry));
    const std::string context = cat(path, " (camera ", c.id, ")");
    const int32_t modelId = in.read<int32_t>(cat("the model of camera ", c.id));
    const LensModelInfo* model = findLensModelByColmapId(modelId);
    if (!model) {
      std::vector<std::string> known;
      for (const LensModelInfo& m : lensModels()) known.push_back(cat(m.colmapId, " ", m.name));
      throw Error(cat(context, ": COLMAP model id ", modelId,
                      " is not supported (supported: ", join(known, ", "), ")"));
    }
    const uint64_t width = in.read<uint64_t>(cat("the width of camera ", c.id));
    const uint64_t height = in.read<uint64_t>(cat("the height of camera ", c.id));
    std::vector<double> params;
    for (size_t p = 0; p < model->paramNames.size(); ++p)
      params.push_back(
          in.read<double>(cat("parameter ", model->paramNames[p], " of camera ", c.id)));
    const auto side = [](uint64_t v) { return v > uint64_t(kMaxImageSide) ? -1LL : (long long)v; };
    c.sensor = colmapSensor(model->id, side(width), side(height), std::move(params), context);
    c.context = context;
    cameras.push_back(std::move(c));
  }
  return cameras;
}

std::vector<ColmapImage> readImagesBinary(const std::string& path) {
  BinaryReader in(path);
  // id, pose, camera id, an empty name's NUL and the point count.
  const uint64_t count = in.readCount(4 + 7 * 8 + 4 + 1 + 8, "the number of images");
  std::vector<ColmapImage> images;
  for (uint64_t k = 0; k < count; ++k) {
    ColmapImage im;
    im.id = in.read<uint32_t>(cat("the id of image #", k + 1));
    const std::string entry = cat("image ", im.id);
    for (double& c : im.q) c = in.read<double>(cat("the rotation of ", entry));
    for (int i = 0; i < 3; ++i) im.t[i] = in.read<double>(cat("the translation of ", entry));
    im.cameraId = in.read<uint32_t>(cat("the camera id of ", entry));
    im.name = in.readName(cat("the name of ", entry));
    im.context = cat(path, " (image ", im.id, " '", im.name, "')");
    const uint64_t points = in.readCount(24, cat("the number of 2D points of ", entry));
    in.skip(size_t(points) * 24, cat("the 2D points of ", entry));
    images.push_back(std::move(im));
  }
  return images;
}

// ---- writing ----

// The COLMAP camera id of each sensor: its own id when all ids are distinct uint32 numbers.
std::vector<uint32_t> colmapCameraIds(const CameraFile& file) {
  std::vector<uint32_t> ids;
  std::set<uint32_t> seen;
  if (file.sensorIds.size() == file.sensors.size()) {
    for (const std::string& s : file.sensorIds) {
      int64_t v = 0;
      if (!parseIntToken(s.data(), s.data() + s.size(), v) || v < 0 || v > kMaxColmapId ||
          !seen.insert(uint32_t(v)).second)
        break;
      ids.push_back(uint32_t(v));
    }
  }
  if (ids.size() != file.sensors.size()) {
    ids.clear();
    for (size_t k = 0; k < file.sensors.size(); ++k) ids.push_back(uint32_t(k + 1));
  }
  return ids;
}

// What both writers check and convert: sensors in COLMAP's pixel convention, image names
// COLMAP can read back, poses as (q, t).
struct ColmapModel {
  std::vector<uint32_t> cameraIds;
  std::vector<CalibratedSensor> sensors;
  std::vector<std::array<double, 4>> q;
  std::vector<glm::dvec3> t;
};

ColmapModel colmapModel(const CameraFile& file, const std::string& dir, bool text) {
  ColmapModel m;
  m.cameraIds = colmapCameraIds(file);
  for (const CalibratedSensor& s : file.sensors)
    m.sensors.push_back(inPixelCentre(s, PixelCentre::HalfInteger));
  for (size_t k = 0; k < file.images.size(); ++k) {
    const CalibratedImage& im = file.images[k];
    const std::string context = cat(dir, ": image ", k + 1, " '", im.name, "'");
    if (im.sensor < 0 || size_t(im.sensor) >= file.sensors.size())
      throw Error(cat(context, ": sensor index ", im.sensor, " is out of range"));
    if (im.name.empty() || im.name.find('\0') != std::string::npos ||
        (text && im.name.find_first_of(" \t\r\n") != std::string::npos))
      throw Error(cat(context, ": COLMAP cannot store this name (", text ? "text" : "binary",
                      " models need a non-empty name without ",
                      text ? "spaces, tabs or line breaks" : "NUL bytes", ")"));
    const glm::dmat4 pose =
        worldToCameraOpenCV(im.worldToCamera, AxisConvention::OpenCV, false, context);
    m.q.push_back(quaternionOfRotation(glm::dmat3(pose)));
    m.t.emplace_back(pose[3]);
  }
  return m;
}

void writeAtomicallyInto(const std::string& dir, const char* name, const std::string& bytes) {
  writeBytesAtomically((fs::path(dir) / name).string(), bytes.data(), bytes.size());
}

void makeFolder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error(cat(dir, ": cannot create the folder (", ec.message(), ")"));
}

}  // namespace

CameraFile readColmapText(const std::string& dir) {
  const std::string cameras = (fs::path(dir) / "cameras.txt").string();
  const std::string images = (fs::path(dir) / "images.txt").string();
  return assemble(dir, CameraFileFormat::ColmapText, readCamerasText(cameras),
                  readImagesText(images));
}

CameraFile readColmapBinary(const std::string& dir) {
  const std::string cameras = (fs::path(dir) / "cameras.bin").string();
  const std::string images = (fs::path(dir) / "images.bin").string();
  return assemble(dir, CameraFileFormat::ColmapBinary, readCamerasBinary(cameras),
                  readImagesBinary(images));
}

}  // namespace aperture::camera_files

namespace aperture {

using camera_files::ColmapModel;

void writeColmapText(const CameraFile& file, const std::string& dir) {
  const ColmapModel m = camera_files::colmapModel(file, dir, true);
  std::ostringstream cameras;
  cameras.precision(17);
  cameras << "# Camera list with one line of data per camera:\n"
          << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
          << "# Number of cameras: " << m.sensors.size() << "\n";
  for (size_t k = 0; k < m.sensors.size(); ++k) {
    const CalibratedSensor& s = m.sensors[k];
    cameras << m.cameraIds[k] << ' ' << s.lens.info().name << ' ' << s.width << ' ' << s.height;
    for (double p : s.lens.params()) cameras << ' ' << p;
    cameras << '\n';
  }
  std::ostringstream images;
  images.precision(17);
  images << "# Image list with two lines of data per image:\n"
         << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
         << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
         << "# Number of images: " << file.images.size() << ", mean observations per image: 0\n";
  for (size_t k = 0; k < file.images.size(); ++k) {
    images << k + 1;
    for (double c : m.q[k]) images << ' ' << c;
    for (int i = 0; i < 3; ++i) images << ' ' << m.t[k][i];
    images << ' ' << m.cameraIds[size_t(file.images[k].sensor)] << ' ' << file.images[k].name
           << "\n\n";
  }
  const std::string points =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: 0, mean track length: 0\n";
  camera_files::makeFolder(dir);
  camera_files::writeAtomicallyInto(dir, "cameras.txt", cameras.str());
  camera_files::writeAtomicallyInto(dir, "images.txt", images.str());
  camera_files::writeAtomicallyInto(dir, "points3D.txt", points);
}

void writeColmapBinary(const CameraFile& file, const std::string& dir) {
  const ColmapModel m = camera_files::colmapModel(file, dir, false);
  std::string cameras;
  appendLittleEndian<uint64_t>(cameras, m.sensors.size());
  for (size_t k = 0; k < m.sensors.size(); ++k) {
    const CalibratedSensor& s = m.sensors[k];
    appendLittleEndian<uint32_t>(cameras, m.cameraIds[k]);
    appendLittleEndian<int32_t>(cameras, s.lens.info().colmapId);
    appendLittleEndian<uint64_t>(cameras, uint64_t(s.width));
    appendLittleEndian<uint64_t>(cameras, uint64_t(s.height));
    for (double p : s.lens.params()) appendLittleEndian<double>(cameras, p);
  }
  std::string images;
  appendLittleEndian<uint64_t>(images, file.images.size());
  for (size_t k = 0; k < file.images.size(); ++k) {
    appendLittleEndian<uint32_t>(images, uint32_t(k + 1));
    for (double c : m.q[k]) appendLittleEndian<double>(images, c);
    for (int i = 0; i < 3; ++i) appendLittleEndian<double>(images, m.t[k][i]);
    appendLittleEndian<uint32_t>(images, m.cameraIds[size_t(file.images[k].sensor)]);
    images += file.images[k].name;
    images.push_back('\0');
    appendLittleEndian<uint64_t>(images, 0);  // no 2D points
  }
  std::string points;
  appendLittleEndian<uint64_t>(points, 0);
  camera_files::makeFolder(dir);
  camera_files::writeAtomicallyInto(dir, "cameras.bin", cameras);
  camera_files::writeAtomicallyInto(dir, "images.bin", images);
  camera_files::writeAtomicallyInto(dir, "points3D.bin", points);
}

}  // namespace aperture
