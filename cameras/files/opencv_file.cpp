// OpenCV-style calibration files, JSON or YAML (OpenCV FileStorage YAML: a first line
// "%YAML:1.0", matrices as !!opencv-matrix maps with rows, cols, dt and row-major data).
//
// Layout. A file holds one camera at the top level, or several:
//   one camera          { "name": "cam0", "K": …, "dist": …, "R": …, "t": …, "width": 1920,
//                         "height": 1080 }          (name optional: the file's stem)
//   a list              { "cameras": [ {camera}, {camera}, … ] }  (name optional: "camera_N")
//   cameras by name     { "cam0": {camera}, "cam1": {camera} }    (the key is the name)
// Per camera:
//   K       3×3 camera matrix [fx 0 cx; 0 fy cy; 0 0 1], pixels; skew (K[0][1] ≠ 0) is refused
//   dist    0, 4, 5, 8, 12 or 14 coefficients in OpenCV's order k1 k2 p1 p2 [k3 [k4 k5 k6
//           [s1 s2 s3 s4 [τx τy]]]] (absent or all zero: no distortion)
//   R       3×3 rotation, or rvec: a Rodrigues vector (axis × angle in radians)
//   t       translation; (R, t) is world-to-camera, x_cam = R·x_world + t, OpenCV axes
//   width, height   the image size in pixels
// A matrix or vector may be a nested list of rows, a flat row-major list, or an OpenCV matrix
// ({"rows", "cols", "data"}, as FileStorage writes it in JSON and YAML).
// Pixel centres are integer: OpenCV puts the centre of pixel (i, j) at (j, i).
//
// dist onto COLMAP's models: 4 → OPENCV; 5 or 8 → FULL_OPENCV (the same rational radial
// factor (1 + k1r² + k2r⁴ + k3r⁶) / (1 + k4r² + k5r⁴ + k6r⁶) and tangential terms); 12 or 14
// → FULL_OPENCV when the thin-prism s1..s4 and tilt τx, τy are all zero. Non-zero thin-prism
// or tilt terms are refused: COLMAP's THIN_PRISM_FISHEYE is a fisheye model and does not
// coincide with them. All-zero dist → PINHOLE.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "cameras/files/camera_file_formats.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"
#include "core/util/mapped_file.h"

namespace aperture::camera_files {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// YAML nodes a file may expand to (aliases can repeat a subtree exponentially often).
constexpr size_t kMaxYamlNodes = 1000000;

// ---- YAML as JSON, so both go through one camera reader ----

json scalarOfYaml(const YAML::Node& node) {
  const std::string& s = node.Scalar();
  if (node.Tag() == "!") return s;  // quoted: a string even when it looks like a number
  int64_t i = 0;
  if (parseIntToken(s.data(), s.data() + s.size(), i)) return i;
  double d = 0;
  if (parseDoubleToken(s.data(), s.data() + s.size(), d)) return d;
  if (s == ".nan" || s == ".NaN" || s == ".NAN") return std::nan("");
  if (s == ".inf" || s == ".Inf" || s == "+.inf") return HUGE_VAL;
  if (s == "-.inf" || s == "-.Inf") return -HUGE_VAL;
  return s;
}

json jsonOfYaml(const YAML::Node& node, size_t& budget, const std::string& path) {
  if (budget-- == 0)
    throw Error(cat(path, ": the YAML expands to more than ", kMaxYamlNodes, " nodes"));
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return scalarOfYaml(node);
    case YAML::NodeType::Sequence: {
      json a = json::array();
      for (const YAML::Node& child : node) a.push_back(jsonOfYaml(child, budget, path));
      return a;
    }
    case YAML::NodeType::Map: {
      json o = json::object();
      for (const auto& kv : node) {
        if (!kv.first.IsScalar())
          throw Error(cat(path, ": line ", kv.first.Mark().line + 1, ": map keys must be text"));
        o[kv.first.Scalar()] = jsonOfYaml(kv.second, budget, path);
      }
      return o;
    }
    default:
      return nullptr;
  }
}

// ---- matrices ----

// Rows × cols numbers, row-major, from a nested list, a flat list or an OpenCV matrix.
std::vector<double> numbers(const json& j, size_t rows, size_t cols, const std::string& context) {
  const size_t n = rows * cols;
  std::vector<double> out;
  const json* flat = &j;
  if (j.is_object() && j.contains("data")) {
    const auto side = [](const json& v) {
      return v.is_number_integer() && v.get<int64_t>() >= 0 && v.get<int64_t>() <= 16
                 ? v.get<int64_t>()
                 : int64_t(-1);
    };
    if (j.contains("rows") && j.contains("cols") && side(j["rows"]) * side(j["cols"]) != int64_t(n))
      throw Error(cat(context, ": an OpenCV matrix of ", shown(j["rows"]), " × ", shown(j["cols"]),
                      ", expected ", rows, " × ", cols));
    flat = &j["data"];
  }
  if (!flat->is_array())
    throw Error(cat(context, ": expected ", rows, " × ", cols, " numbers, got ", shown(j)));
  for (const json& item : *flat) {
    if (item.is_array()) {
      for (const json& x : item) out.push_back(finiteNumber(x, context));
    } else {
      out.push_back(finiteNumber(item, context));
    }
    if (out.size() > n) break;
  }
  if (out.size() != n)
    throw Error(cat(context, ": expected ", rows, " × ", cols, " numbers, got ",
                    out.size() > n ? "more" : std::to_string(out.size())));
  return out;
}

// Any number of coefficients (dist), from the same shapes.
std::vector<double> coefficientList(const json& j, const std::string& context) {
  const json& flat = j.is_object() && j.contains("data") ? j["data"] : j;
  if (!flat.is_array()) throw Error(cat(context, ": expected a list of numbers, got ", shown(j)));
  std::vector<double> out;
  for (const json& item : flat) {
    if (item.is_array()) {
      for (const json& x : item) out.push_back(finiteNumber(x, context));
    } else {
      out.push_back(finiteNumber(item, context));
    }
    if (out.size() > 14) throw Error(cat(context, ": more than 14 distortion coefficients"));
  }
  return out;
}

// Rodrigues: the rotation by |r| radians about r / |r|.
glm::dmat3 rotationOfRodrigues(const glm::dvec3& r) {
  const double angle = glm::length(r);
  if (angle == 0) return glm::dmat3(1.0);
  const glm::dvec3 k = r / angle;
  const double c = std::cos(angle), s = std::sin(angle);
  glm::dmat3 m;
  // m[col][row] = cos δ + (1 − cos) k_row k_col + sin [k]×(row, col)
  const double cross[3][3] = {{0, -k.z, k.y}, {k.z, 0, -k.x}, {-k.y, k.x, 0}};
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col)
      m[col][row] = (row == col ? c : 0.0) + (1 - c) * k[row] * k[col] + s * cross[row][col];
  return m;
}

Lens openCVCameraLens(const std::vector<double>& K, const std::vector<double>& dist,
                      const std::string& context) {
  if (K[1] != 0)
    throw Error(cat(context, ": K has skew K[0][1] = ", K[1],
                    " (not supported: COLMAP's models "
                    "have none)"));
  if (K[3] != 0 || K[6] != 0 || K[7] != 0 || K[8] != 1)
    throw Error(cat(context, ": K must be [fx 0 cx; 0 fy cy; 0 0 1], got rows (", K[0], " ", K[1],
                    " ", K[2], "; ", K[3], " ", K[4], " ", K[5], "; ", K[6], " ", K[7], " ", K[8],
                    ")"));
  const double fx = K[0], fy = K[4], cx = K[2], cy = K[5];
  const size_t n = dist.size();
  if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
    throw Error(cat(context, ": dist has ", n,
                    " coefficients; OpenCV's models take 4, 5, 8, 12 or 14 (k1 k2 p1 p2 [k3 [k4 "
                    "k5 k6 [s1 s2 s3 s4 [τx τy]]]])"));
  const char* extraNames[] = {"s1", "s2", "s3", "s4", "τx", "τy"};
  for (size_t i = 8; i < n; ++i)
    if (dist[i] != 0)
      throw Error(cat(context, ": dist ", extraNames[i - 8], " = ", dist[i],
                      ": OpenCV's thin-prism and tilt terms are not supported (COLMAP's "
                      "THIN_PRISM_FISHEYE is a fisheye model and does not coincide with them)"));
  // The first model, in the table's order, whose OpenCV slots take the coefficients: every one
  // given (zeros alone: any model that holds them), the standard model, two focal lengths.
  bool zero = true;
  for (double d : dist) zero &= d == 0;
  const std::vector<double> given(dist.begin(), dist.begin() + long(std::min<size_t>(n, 8)));
  for (const LensModelInfo& m : lensModels()) {
    if (!m.opencv.expressible() || std::string(m.opencv.name) != "standard" || m.singleFocal())
      continue;
    if (!zero && m.opencv.slots.size() < given.size()) continue;
    const auto lens = withContext(context, [&] {
      return lensOfSlots(m, {fx, fy, cx, cy}, m.opencv, given);
    });
    if (lens) return *lens;
  }
  throw Error(cat(context, ": no camera model holds dist (",
                  join(given, " ", [](double d) { return cat(d); }), ")"));
}

struct NamedCamera {
  std::string name;
  const json* camera;
  std::string context;
};

// The cameras of a document in file order (see the layout above).
std::vector<NamedCamera> camerasOf(const json& doc, const std::string& path) {
  if (!doc.is_object())
    throw Error(cat(path,
                    ": expected an object with a camera (K, …), a 'cameras' list or "
                    "cameras by name"));
  std::vector<NamedCamera> cameras;
  if (doc.contains("K")) {
    const std::string name = doc.contains("name") && doc["name"].is_string()
                                 ? doc["name"].get<std::string>()
                                 : fs::path(path).stem().string();
    cameras.push_back({name, &doc, cat(path, ": camera '", name, "'")});
  } else if (doc.contains("cameras")) {
    const json& list = doc["cameras"];
    if (!list.is_array()) throw Error(cat(path, ": 'cameras' must be a list"));
    for (size_t i = 0; i < list.size(); ++i) {
      const json& c = list[i];
      const std::string name = c.is_object() && c.contains("name") && c["name"].is_string()
                                   ? c["name"].get<std::string>()
                                   : cat("camera_", i);
      cameras.push_back({name, &c, cat(path, ": cameras[", i, "] ('", name, "')")});
    }
  } else {
    for (const auto& [key, value] : doc.items())
      if (value.is_object() && value.contains("K"))
        cameras.push_back({key, &value, cat(path, ": camera '", key, "'")});
  }
  if (cameras.empty())
    throw Error(cat(path,
                    ": no camera found (expected K at the top level, a 'cameras' list, or "
                    "objects with K by name)"));
  return cameras;
}

CameraFile readOpenCVDocument(const std::string& path, const json& doc, CameraFileFormat format) {
  CameraFile file;
  file.path = path;
  file.format = format;
  std::map<std::string, std::string> contextOfName;
  for (const NamedCamera& nc : camerasOf(doc, path)) {
    const json& c = *nc.camera;
    const std::string& context = nc.context;
    if (!c.is_object()) throw Error(cat(context, ": expected an object, got ", shown(c)));
    const auto [it, fresh] = contextOfName.emplace(nc.name, context);
    if (!fresh)
      throw Error(
          cat(context, ": the name '", nc.name, "' is given twice (also ", it->second, ")"));
    for (const char* key : {"K", "t", "width", "height"})
      if (!c.contains(key))
        throw Error(cat(context, ": needs '", key, "'",
                        key[0] == 'w' || key[0] == 'h' ? " (the image size is missing)" : ""));
    const std::vector<double> K = numbers(c["K"], 3, 3, context + " K");
    const std::vector<double> dist =
        c.contains("dist") ? coefficientList(c["dist"], context + " dist") : std::vector<double>{};
    const CalibratedSensor sensor{imageSide(c["width"], context + " width"),
                                  imageSide(c["height"], context + " height"),
                                  openCVCameraLens(K, dist, context), PixelCentre::Integer};
    glm::dmat3 rotation;
    if (c.contains("R") == c.contains("rvec"))
      throw Error(cat(context, ": give the rotation as either R (3×3) or rvec (Rodrigues)"));
    if (c.contains("R")) {
      const std::vector<double> r = numbers(c["R"], 3, 3, context + " R");
      for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 3; ++col) rotation[col][row] = r[size_t(row * 3 + col)];
    } else {
      const std::vector<double> r = numbers(c["rvec"], 3, 1, context + " rvec");
      rotation = rotationOfRodrigues({r[0], r[1], r[2]});
    }
    const std::vector<double> t = numbers(c["t"], 3, 1, context + " t");
    glm::dmat4 pose(rotation);
    pose[3] = glm::dvec4(t[0], t[1], t[2], 1.0);
    file.images.push_back({nc.name, shareSensor(file, sensor),
                           worldToCameraOpenCV(pose, AxisConvention::OpenCV, false, context)});
  }
  return file;
}

}  // namespace

CameraFile readOpenCVJson(const std::string& path, const json& doc) {
  return readOpenCVDocument(path, doc, CameraFileFormat::OpenCVJson);
}

CameraFile readOpenCVYaml(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat(path, ": cannot open the file"));
  std::ostringstream s;
  s << in.rdbuf();
  std::string text = s.str();
  // OpenCV's "%YAML:1.0" is not a YAML directive; it becomes a comment (line numbers stay).
  if (text.rfind("%YAML:", 0) == 0) text.insert(0, "#");
  json doc;
  try {
    size_t budget = kMaxYamlNodes;
    doc = jsonOfYaml(YAML::Load(text), budget, path);
  } catch (const YAML::Exception& e) {
    throw Error(cat(path, ": not valid YAML (", e.what(), ")"));
  }
  return readOpenCVDocument(path, doc, CameraFileFormat::OpenCVYaml);
}

}  // namespace aperture::camera_files

namespace aperture {

void writeOpenCVJson(const CameraFile& file, const std::string& path) {
  using nlohmann::json;
  json cameras = json::array();
  for (const CalibratedImage& im : file.images) {
    const std::string context = cat(path, ": image '", im.name, "'");
    if (im.sensor < 0 || size_t(im.sensor) >= file.sensors.size())
      throw Error(cat(context, ": sensor index ", im.sensor, " is out of range"));
    const CalibratedSensor s =
        camera_files::inPixelCentre(file.sensors[size_t(im.sensor)], PixelCentre::Integer);
    const auto cv = camera_files::openCVLens(s.lens);
    if (!cv || cv->fisheye)
      throw Error(cat(context, ": its lens ", s.lens.info().name,
                      " is not OpenCV's standard model (fisheye lenses are not written to OpenCV "
                      "files)"));
    const glm::dmat4 pose =
        worldToCameraOpenCV(im.worldToCamera, AxisConvention::OpenCV, false, context);
    json c;
    c["name"] = im.name;
    c["width"] = s.width;
    c["height"] = s.height;
    c["K"] = {{s.lens.fx(), 0.0, s.lens.cx()}, {0.0, s.lens.fy(), s.lens.cy()}, {0.0, 0.0, 1.0}};
    c["dist"] = cv->dist;
    c["R"] = json::array();
    for (int row = 0; row < 3; ++row) c["R"].push_back({pose[0][row], pose[1][row], pose[2][row]});
    c["t"] = {pose[3][0], pose[3][1], pose[3][2]};
    cameras.push_back(std::move(c));
  }
  json doc;
  doc["cameras"] = std::move(cameras);
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  writeTextAtomically(path, camera_files::jsonFileText(doc, path));
}

}  // namespace aperture
