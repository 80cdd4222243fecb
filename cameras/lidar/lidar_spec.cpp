// Reading LiDAR sensors: aperture's JSON spec, Ouster's sensor metadata (legacy flat and
// nested), Velodyne's calibration YAML (ROS velodyne_pointcloud), Livox's scan-mode CSV
// (livox_laser_simulation) and the presets. docs/lidar.md documents each.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "cameras/lidar/lidar.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

const std::vector<std::pair<std::string, std::string>>& lidarPresetFiles();  // generated

namespace {

using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat(path, ": cannot open the LiDAR spec"));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string directoryOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

std::string stemOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

// Typed reads of JSON fields, each error naming the source and the field.
struct Fields {
  const json& doc;
  std::string source;  // "path" or "path: ouster_metadata"
  std::string prefix;  // "beam_intrinsics." for nested objects

  std::string where(const std::string& key) const {
    return cat(source, ": field '", prefix, key, "'");
  }
  bool has(const std::string& key) const { return doc.is_object() && doc.contains(key); }
  const json& at(const std::string& key) const {
    if (!has(key)) throw Error(cat(where(key), " is missing"));
    return doc.at(key);
  }
  double number(const std::string& key) const {
    const json& v = at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      throw Error(cat(where(key), ": ", v.dump(), " is not a finite number"));
    return v.get<double>();
  }
  double number(const std::string& key, double fallback) const {
    return has(key) ? number(key) : fallback;
  }
  int64_t integer(const std::string& key) const {
    const json& v = at(key);
    if (!v.is_number_integer() &&
        !(v.is_number() && std::floor(v.get<double>()) == v.get<double>()))
      throw Error(cat(where(key), ": ", v.dump(), " is not an integer"));
    return v.is_number_integer() ? v.get<int64_t>() : int64_t(v.get<double>());
  }
  std::string text(const std::string& key) const {
    const json& v = at(key);
    if (!v.is_string()) throw Error(cat(where(key), ": ", v.dump(), " is not a string"));
    return v.get<std::string>();
  }
  std::vector<double> numbers(const std::string& key) const {
    const json& v = at(key);
    if (!v.is_array()) throw Error(cat(where(key), " is not a list of numbers"));
    std::vector<double> out;
    for (size_t i = 0; i < v.size(); ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
        throw Error(cat(where(key), "[", i, "]: ", v[i].dump(), " is not a finite number"));
      out.push_back(v[i].get<double>());
    }
    return out;
  }
  std::vector<int64_t> integers(const std::string& key) const {
    const std::vector<double> v = numbers(key);
    std::vector<int64_t> out;
    for (size_t i = 0; i < v.size(); ++i) {
      if (std::floor(v[i]) != v[i] || std::fabs(v[i]) > 9e15)
        throw Error(cat(where(key), "[", i, "]: ", v[i], " is not an integer"));
      out.push_back(int64_t(v[i]));
    }
    return out;
  }
  // A 4x4 matrix given as 16 numbers row by row (Ouster's layout).
  glm::dmat4 matrix(const std::string& key) const {
    std::vector<double> v;
    const json& j = at(key);
    if (j.is_array() && !j.empty() && j[0].is_array()) {
      for (size_t r = 0; r < j.size(); ++r) {
        for (const json& x : j[r]) {
          if (!x.is_number()) throw Error(cat(where(key), ": rows of numbers expected"));
          v.push_back(x.get<double>());
        }
      }
    } else {
      v = numbers(key);
    }
    if (v.size() != 16)
      throw Error(cat(where(key), ": a 4x4 matrix holds 16 numbers, not ", v.size()));
    glm::dmat4 m(1.0);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m[c][r] = v[size_t(r * 4 + c)];
    return m;
  }
  // Rejects keys outside `known`, with "did you mean".
  void onlyKnown(const std::vector<std::string>& known) const {
    for (auto it = doc.begin(); it != doc.end(); ++it)
      if (std::find(known.begin(), known.end(), it.key()) == known.end())
        throw Error(
            cat(source, ": unknown field '", prefix, it.key(), "'", didYouMean(it.key(), known)));
  }
};

// Throws unless m is a rigid transform (orthonormal rotation block, last row 0 0 0 1).
void requireRigid(const glm::dmat4& m, const std::string& where) {
  const glm::dmat3 r(m);
  const glm::dmat3 e = glm::transpose(r) * r - glm::dmat3(1.0);
  double err = 0;
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) err = std::max(err, std::fabs(e[c][k]));
  if (err > 1e-4 || glm::determinant(r) < 0 || m[0][3] != 0 || m[1][3] != 0 || m[2][3] != 0 ||
      m[3][3] != 1)
    throw Error(cat(where, ": not a rigid transform (rotation error ", err, ")"));
}

// --- Ouster ----------------------------------------------------------------------------------

// Ouster's sensor metadata, as ouster-sdk reads it (ouster_core/src/metadata.cpp): a legacy
// file holds its fields at the top level (data_format for lidar_data_format), a newer one in
// beam_intrinsics, lidar_intrinsics, lidar_data_format, config_params and sensor_info.
LidarSensor readOuster(const json& doc, const std::string& source) {
  const bool nested = doc.contains("beam_intrinsics");
  auto section = [&](const char* nestedName, const char* legacyName) -> Fields {
    const char* name = nested ? nestedName : legacyName;
    if (name == nullptr) return Fields{doc, source, ""};
    if (doc.contains(name)) {
      if (!doc.at(name).is_object())
        throw Error(cat(source, ": field '", name, "' is not an object"));
      return Fields{doc.at(name), source, cat(name, ".")};
    }
    static const json empty = json::object();
    return Fields{empty, source, cat(name, ".")};
  };
  const Fields beamsF = section("beam_intrinsics", nullptr);
  const Fields lidarF = section("lidar_intrinsics", nullptr);
  const Fields formatF = section("lidar_data_format", "data_format");
  const Fields configF = section("config_params", nullptr);
  const Fields infoF = section("sensor_info", nullptr);

  LidarSensor s;
  s.source = {source, "ouster"};
  s.kind = LidarKind::Spinning;
  const std::vector<double> altitude = beamsF.numbers("beam_altitude_angles");
  const std::vector<double> azimuth = beamsF.numbers("beam_azimuth_angles");
  if (altitude.empty()) throw Error(cat(beamsF.where("beam_altitude_angles"), " is empty"));
  if (azimuth.size() != altitude.size())
    throw Error(cat(beamsF.where("beam_azimuth_angles"), " has ", azimuth.size(),
                    " entries, beam_altitude_angles ", altitude.size(),
                    " (one per beam; per-pixel tables of flash sensors are not read)"));
  const size_t h = altitude.size();
  if (formatF.has("pixels_per_column") && size_t(formatF.integer("pixels_per_column")) != h)
    throw Error(cat(formatF.where("pixels_per_column"), ": ", formatF.integer("pixels_per_column"),
                    ", but beam_altitude_angles has ", h, " entries"));

  // Columns and rate: the data format, else the lidar mode "1024x10".
  std::optional<int64_t> modeColumns, modeFps;
  if (configF.has("lidar_mode")) {
    const std::string mode = configF.text("lidar_mode");
    const size_t x = mode.find('x');
    try {
      if (x == std::string::npos) throw std::invalid_argument(mode);
      modeColumns = std::stoll(mode.substr(0, x));
      modeFps = std::stoll(mode.substr(x + 1));
    } catch (const std::exception&) {
      throw Error(cat(configF.where("lidar_mode"), ": '", mode, "' is not COLUMNSxFPS"));
    }
  }
  if (formatF.has("columns_per_frame"))
    s.columns = int(formatF.integer("columns_per_frame"));
  else if (modeColumns)
    s.columns = int(*modeColumns);
  else
    throw Error(cat(formatF.where("columns_per_frame"), " is missing (and no ", configF.prefix,
                    "lidar_mode gives it)"));
  if (modeColumns && *modeColumns != s.columns)
    throw Error(cat(formatF.where("columns_per_frame"), ": ", s.columns, " does not match ",
                    configF.prefix, "lidar_mode (", *modeColumns, ")"));
  if (formatF.has("fps"))
    s.sweepRateHz = formatF.number("fps");
  else if (modeFps)
    s.sweepRateHz = double(*modeFps);
  else
    throw Error(cat(configF.where("lidar_mode"), " is missing (and no ", formatF.prefix,
                    "fps gives the rate)"));

  if (formatF.has("column_window")) {
    const std::vector<int64_t> w = formatF.integers("column_window");
    if (w.size() != 2)
      throw Error(cat(formatF.where("column_window"), ": two measurement ids, not ", w.size()));
    s.columnWindow = {int(w[0]), int(w[1])};
  } else {
    s.columnWindow = {0, s.columns - 1};
  }
  if (formatF.has("pixel_shift_by_row")) {
    for (int64_t v : formatF.integers("pixel_shift_by_row")) s.pixelShiftByRow.push_back(int(v));
    if (s.pixelShiftByRow.size() != h)
      throw Error(cat(formatF.where("pixel_shift_by_row"), " has ", s.pixelShiftByRow.size(),
                      " entries, the beam table ", h));
  } else if (h == 64 &&
             (s.columns == 512 || s.columns == 1024 || s.columns == 2048 || s.columns == 4096)) {
    // ouster-sdk's default data format (data_format.cpp): {3k, 2k, k, 0} repeated.
    const int k = 3 * s.columns / 512;
    for (size_t i = 0; i < h; ++i) s.pixelShiftByRow.push_back(k * (3 - int(i % 4)));
  } else {
    s.pixelShiftByRow.assign(h, 0);
  }

  // Beam origins. ouster-sdk: n = beam_to_lidar(0,3), or |(b03, b23)| when b23 != 0; the
  // default beam_to_lidar is the identity with b03 = lidar_origin_to_beam_origin_mm, whose own
  // default depends on the product line.
  std::string prodLine = infoF.has("prod_line") ? infoF.text("prod_line") : "";
  double originMm = 12.163;
  if (prodLine.rfind("OS-0-", 0) == 0) originMm = 27.67;
  if (prodLine.rfind("OS-1-", 0) == 0) originMm = 15.806;
  if (prodLine.rfind("OS-2-", 0) == 0) originMm = 13.762;
  if (beamsF.has("lidar_origin_to_beam_origin_mm"))
    originMm = beamsF.number("lidar_origin_to_beam_origin_mm");
  glm::dmat4 beamToLidar(1.0);
  beamToLidar[3][0] = originMm;
  if (beamsF.has("beam_to_lidar_transform")) beamToLidar = beamsF.matrix("beam_to_lidar_transform");
  const double b03 = beamToLidar[3][0], b23 = beamToLidar[3][2];
  const double n = b23 != 0 ? std::sqrt(b03 * b03 + b23 * b23) : b03;

  glm::dmat4 lidarToSensor(1.0);
  lidarToSensor[0][0] = -1;
  lidarToSensor[1][1] = -1;
  lidarToSensor[3][2] = 36.18;  // ouster-sdk's DEFAULT_LIDAR_TO_SENSOR
  if (lidarF.has("lidar_to_sensor_transform"))
    lidarToSensor = lidarF.matrix("lidar_to_sensor_transform");
  requireRigid(lidarToSensor, lidarF.where("lidar_to_sensor_transform"));
  lidarToSensor[3] = glm::dvec4(glm::dvec3(lidarToSensor[3]) * 0.001, 1.0);  // mm to m
  s.sensorFromLidar = lidarToSensor;

  for (size_t i = 0; i < h; ++i) {
    LidarBeam b;
    b.elevationDeg = altitude[i];
    b.azimuthDeg = -azimuth[i];  // ouster-sdk: θ_a = −beam_azimuth_angles
    b.origin = glm::dvec3(b03, 0.0, b23) * 0.001;
    b.rangeOffset = n * 0.001;
    s.beams.push_back(b);
  }
  // Encoder angle θ_e = 2π − m·2π/w: column 0 at +x, turning clockwise.
  s.firstColumnAzimuthDeg = 0;
  s.spin = -1;
  s.minRange = 0;
  s.maxRange = 1e9;
  if (configF.has("min_range_threshold_cm"))
    s.minRange = configF.number("min_range_threshold_cm") * 0.01;
  s.name = prodLine.empty() ? "ouster" : prodLine;
  return s;
}

// --- Velodyne --------------------------------------------------------------------------------

json jsonOfYaml(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar: {
      const std::string s = node.Scalar();
      char* end = nullptr;
      const double v = std::strtod(s.c_str(), &end);
      if (!s.empty() && end == s.c_str() + s.size()) {
        if (s.find_first_of(".eE") == std::string::npos && std::fabs(v) < 9e15)
          return json(int64_t(v));
        return json(v);
      }
      return json(s);
    }
    case YAML::NodeType::Sequence: {
      json a = json::array();
      for (const YAML::Node& child : node) a.push_back(jsonOfYaml(child));
      return a;
    }
    case YAML::NodeType::Map: {
      json o = json::object();
      for (const auto& kv : node) o[kv.first.Scalar()] = jsonOfYaml(kv.second);
      return o;
    }
    default:
      return json();
  }
}

// The ROS velodyne_pointcloud driver's calibration (calibration.cc, rawdata.cc): angles in
// radians, offsets in metres. Its point of a laser at rotation α' = rotation − rot_correction
// and distance d, in ROS axes, is
//   (d·cos v·cos α' − vo·sin v·cos α' + h·sin α', −d·cos v·sin α' + vo·sin v·sin α' + h·cos α',
//    d·sin v + vo·cos v),
// so its azimuth is ψ = −rotation + rot_correction and its origin Rz(ψ)·(−vo·sin v, h, vo·cos v).
LidarSensor readVelodyne(const json& doc, const std::string& source) {
  const Fields top{doc, source, ""};
  const json& lasers = top.at("lasers");
  if (!lasers.is_array() || lasers.empty())
    throw Error(cat(top.where("lasers"), " is not a list of lasers"));
  if (top.has("num_lasers") && size_t(top.integer("num_lasers")) != lasers.size())
    throw Error(cat(top.where("num_lasers"), ": ", top.integer("num_lasers"),
                    ", but 'lasers' holds ", lasers.size()));
  LidarSensor s;
  s.source = {source, "velodyne"};
  s.beams.assign(lasers.size(), LidarBeam{});
  std::vector<bool> seen(lasers.size(), false);
  for (size_t i = 0; i < lasers.size(); ++i) {
    const Fields f{lasers[i], source, cat("lasers[", i, "].")};
    const int64_t id = f.integer("laser_id");
    if (id < 0 || size_t(id) >= lasers.size() || seen[size_t(id)])
      throw Error(cat(f.where("laser_id"), ": ", id, " is out of range or repeated (ids 0 to ",
                      lasers.size() - 1, " once each)"));
    seen[size_t(id)] = true;
    const double v = f.number("vert_correction");
    const double rot = f.number("rot_correction");
    const double vo = f.number("vert_offset_correction", 0.0);
    const double ho = f.number("horiz_offset_correction", 0.0);
    LidarBeam& b = s.beams[size_t(id)];
    b.elevationDeg = v / kDeg;
    b.azimuthDeg = rot / kDeg;
    const glm::dvec3 o(-vo * std::sin(v), ho, vo * std::cos(v));
    b.origin = {o.x * std::cos(rot) - o.y * std::sin(rot),
                o.x * std::sin(rot) + o.y * std::cos(rot), o.z};
    b.distCorrection = f.number("dist_correction", 0.0);
  }
  s.spin = -1;
  s.firstColumnAzimuthDeg = 0;
  s.sweepRateHz = 10;  // the driver's default rpm, 600
  s.columns = 1800;    // 0.2°: aperture's default, a spec's "columns" overrides it
  s.columnWindow = {0, s.columns - 1};
  s.minRange = 0.4;  // the driver's default min_range
  s.maxRange = 130;  // the driver's default max_range
  s.name = "velodyne";
  return s;
}

// --- Livox -----------------------------------------------------------------------------------

// livox_laser_simulation's scan_mode CSV: a header line, then rows "time (s), azimuth (deg),
// zenith (deg)"; its plugin aims a ray at yaw = azimuth, pitch = zenith − 90°, which is the
// direction of elevation 90° − zenith.
std::vector<PatternRay> readLivoxCsv(const std::string& text, const std::string& source) {
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);  // header
  std::vector<PatternRay> rays;
  int n = 1;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    std::vector<std::string> cells;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    const std::string where = cat(source, " line ", n);
    if (cells.size() < 3)
      throw Error(cat(where, ": a pattern row holds time, azimuth, zenith; found ", cells.size(),
                      " values"));
    PatternRay r;
    r.timeNs = parseTimeNs(cells[0], where);
    double v[2];
    for (int k = 0; k < 2; ++k) {
      char* end = nullptr;
      v[k] = std::strtod(cells[size_t(k) + 1].c_str(), &end);
      if (end == cells[size_t(k) + 1].c_str() || !std::isfinite(v[k]))
        throw Error(cat(where, ": '", cells[size_t(k) + 1], "' is not a number"));
    }
    r.azimuthDeg = v[0];
    r.elevationDeg = 90.0 - v[1];
    if (!rays.empty() && r.timeNs < rays.back().timeNs)
      throw Error(cat(where, ": time ", cells[0], " is before the row above"));
    rays.push_back(r);
  }
  if (rays.empty()) throw Error(cat(source, ": no pattern rows"));
  return rays;
}

// The period a pattern repeats with when none is given: its span plus one mean step.
int64_t defaultPatternPeriod(const std::vector<PatternRay>& p) {
  const int64_t span = p.back().timeNs - p.front().timeNs;
  const int64_t step = p.size() > 1 ? span / int64_t(p.size() - 1) : 0;
  return std::max<int64_t>(p.back().timeNs + std::max<int64_t>(step, 1), 1);
}

LidarSensor patternSensor(std::vector<PatternRay> rays, const std::string& source) {
  LidarSensor s;
  s.source = {source, "livox"};
  s.kind = LidarKind::Pattern;
  s.pattern = std::move(rays);
  s.patternPeriodNs = defaultPatternPeriod(s.pattern);
  s.sweepRateHz = 10;
  s.name = "pattern";
  return s;
}

// --- dispatch --------------------------------------------------------------------------------

bool looksLikeJson(const std::string& text) {
  const size_t i = text.find_first_not_of(" \t\r\n");
  return i != std::string::npos && text[i] == '{';
}

bool isOusterJson(const json& doc) {
  return doc.contains("beam_intrinsics") || doc.contains("beam_altitude_angles");
}

json parseJson(const std::string& text, const std::string& source) {
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    throw Error(cat(source, ": not valid JSON (", e.what(), ")"));
  }
}

LidarSensor readVelodyneYaml(const std::string& text, const std::string& source) {
  YAML::Node node;
  try {
    node = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(cat(source, ": not valid YAML (", e.what(), ")"));
  }
  if (!node.IsMap() || !node["lasers"])
    throw Error(cat(source, ": neither JSON, a Velodyne calibration (no 'lasers') nor a CSV"));
  return readVelodyne(jsonOfYaml(node), source);
}

// A vendor file by its content: Ouster JSON, Velodyne YAML, Livox CSV.
LidarSensor readVendorText(const std::string& text, const std::string& source) {
  if (looksLikeJson(text)) {
    const json doc = parseJson(text, source);
    if (!isOusterJson(doc))
      throw Error(cat(source,
                      ": a JSON file without beam_intrinsics or beam_altitude_angles is "
                      "not Ouster metadata"));
    return readOuster(doc, source);
  }
  const size_t firstLine = text.find('\n');
  const std::string head = text.substr(0, firstLine);
  if (text.find("lasers") != std::string::npos && head.find(',') == std::string::npos)
    return readVelodyneYaml(text, source);
  return patternSensor(readLivoxCsv(text, source), source);
}

const std::vector<std::string> kSpecKeys = {"name",
                                            "source",
                                            "type",
                                            "from",
                                            "ouster_metadata",
                                            "velodyne_calibration",
                                            "beams",
                                            "columns",
                                            "sweep_rate_hz",
                                            "column_time_ns",
                                            "first_column_azimuth_deg",
                                            "spin",
                                            "min_range_m",
                                            "max_range_m",
                                            "sensor_from_lidar",
                                            "pixel_shift_by_row",
                                            "column_window",
                                            "pattern",
                                            "pattern_csv",
                                            "pattern_period_s"};
const std::vector<std::string> kBeamKeys = {"elevation_deg", "azimuth_deg", "time_offset_ns",
                                            "origin_m", "range_offset_m"};

// aperture's own spec: a beam table or a vendor base ("from", "ouster_metadata",
// "velodyne_calibration"), then the fields it gives over the base's.
LidarSensor readApertureSpec(const json& doc, const std::string& source, const std::string& dir) {
  if (!doc.is_object()) throw Error(cat(source, ": a LiDAR spec is a JSON object"));
  const Fields f{doc, source, ""};
  f.onlyKnown(kSpecKeys);
  int bases = int(f.has("from")) + int(f.has("ouster_metadata")) +
              int(f.has("velodyne_calibration")) + int(f.has("pattern")) +
              int(f.has("pattern_csv"));
  if (bases > 1)
    throw Error(cat(source,
                    ": give one of 'from', 'ouster_metadata', 'velodyne_calibration', "
                    "'pattern', 'pattern_csv'"));
  LidarSensor s;
  bool haveBase = true;
  if (f.has("from")) {
    std::string path = f.text("from");
    if (!path.empty() && path[0] != '/') path = dir + path;
    s = readVendorText(readText(path), path);
  } else if (f.has("ouster_metadata")) {
    s = readOuster(f.at("ouster_metadata"), cat(source, ": ouster_metadata"));
  } else if (f.has("velodyne_calibration")) {
    s = readVelodyne(f.at("velodyne_calibration"), cat(source, ": velodyne_calibration"));
  } else if (f.has("pattern_csv")) {
    std::string path = f.text("pattern_csv");
    if (!path.empty() && path[0] != '/') path = dir + path;
    s = patternSensor(readLivoxCsv(readText(path), path), path);
  } else if (f.has("pattern")) {
    const json& rows = f.at("pattern");
    if (!rows.is_array() || rows.empty())
      throw Error(
          cat(f.where("pattern"), " is not a list of [time_s, azimuth_deg, elevation_deg]"));
    std::vector<PatternRay> rays;
    for (size_t i = 0; i < rows.size(); ++i) {
      if (!rows[i].is_array() || rows[i].size() != 3)
        throw Error(
            cat(source, ": field 'pattern[", i, "]' is not [time_s, azimuth_deg, elevation_deg]"));
      for (const json& x : rows[i])
        if (!x.is_number() || !std::isfinite(x.get<double>()))
          throw Error(cat(source, ": field 'pattern[", i, "]' holds ", x.dump()));
      PatternRay r;
      r.timeNs = std::llround(rows[i][0].get<double>() * 1e9);
      r.azimuthDeg = rows[i][1].get<double>();
      r.elevationDeg = rows[i][2].get<double>();
      rays.push_back(r);
    }
    s = patternSensor(std::move(rays), source);
  } else {
    haveBase = false;
    s.kind = LidarKind::Spinning;
  }
  s.source = {source, haveBase ? s.source.format + " in aperture" : "aperture"};
  if (f.has("type")) {
    const std::string type = f.text("type");
    if (type != "spinning" && type != "pattern")
      throw Error(cat(f.where("type"), ": '", type, "' is neither 'spinning' nor 'pattern'",
                      didYouMean(type, {"spinning", "pattern"})));
    const LidarKind kind = type == "spinning" ? LidarKind::Spinning : LidarKind::Pattern;
    if (haveBase && kind != s.kind)
      throw Error(cat(f.where("type"), ": '", type, "', but the base sensor is not"));
    s.kind = kind;
  }

  // The beam table: every given array replaces its field; lengths must agree.
  if (f.has("beams")) {
    if (s.kind != LidarKind::Spinning)
      throw Error(cat(f.where("beams"), ": a pattern sensor has no beam table"));
    const Fields b{f.at("beams"), source, "beams."};
    if (!b.doc.is_object())
      throw Error(cat(f.where("beams"), " is not an object of per-beam lists"));
    b.onlyKnown(kBeamKeys);
    if (!haveBase) {
      const std::vector<double> el = b.numbers("elevation_deg");
      if (el.empty()) throw Error(cat(b.where("elevation_deg"), " is empty"));
      s.beams.assign(el.size(), LidarBeam{});
    }
    const size_t n = s.beams.size();
    auto requireLength = [&](const std::string& key, size_t got) {
      if (got != n) throw Error(cat(b.where(key), " has ", got, " entries, the beam table ", n));
    };
    if (b.has("elevation_deg")) {
      const std::vector<double> v = b.numbers("elevation_deg");
      requireLength("elevation_deg", v.size());
      for (size_t i = 0; i < n; ++i) s.beams[i].elevationDeg = v[i];
    }
    if (b.has("azimuth_deg")) {
      const std::vector<double> v = b.numbers("azimuth_deg");
      requireLength("azimuth_deg", v.size());
      for (size_t i = 0; i < n; ++i) s.beams[i].azimuthDeg = v[i];
    }
    if (b.has("time_offset_ns")) {
      const std::vector<int64_t> v = b.integers("time_offset_ns");
      requireLength("time_offset_ns", v.size());
      for (size_t i = 0; i < n; ++i) s.beams[i].timeOffsetNs = v[i];
    }
    if (b.has("range_offset_m")) {
      const std::vector<double> v = b.numbers("range_offset_m");
      requireLength("range_offset_m", v.size());
      for (size_t i = 0; i < n; ++i) s.beams[i].rangeOffset = v[i];
    }
    if (b.has("origin_m")) {
      const json& o = b.at("origin_m");
      if (!o.is_array()) throw Error(cat(b.where("origin_m"), " is not a list of [x, y, z]"));
      requireLength("origin_m", o.size());
      for (size_t i = 0; i < n; ++i) {
        if (!o[i].is_array() || o[i].size() != 3)
          throw Error(cat(source, ": field 'beams.origin_m[", i, "]' is not [x, y, z]"));
        for (int k = 0; k < 3; ++k) {
          if (!o[i][size_t(k)].is_number())
            throw Error(cat(source, ": field 'beams.origin_m[", i, "]' holds ", o[i].dump()));
          s.beams[i].origin[k] = o[i][size_t(k)].get<double>();
        }
      }
    }
  } else if (!haveBase) {
    throw Error(cat(f.where("beams"),
                    " is missing (or give 'from', 'ouster_metadata', "
                    "'velodyne_calibration', 'pattern' or 'pattern_csv')"));
  }

  if (f.has("columns")) s.columns = int(std::clamp<int64_t>(f.integer("columns"), -1, 1 << 30));
  if (!haveBase && s.kind == LidarKind::Spinning && !f.has("columns"))
    throw Error(cat(f.where("columns"), " is missing"));
  if (f.has("sweep_rate_hz"))
    s.sweepRateHz = f.number("sweep_rate_hz");
  else if (!haveBase)
    throw Error(cat(f.where("sweep_rate_hz"), " is missing"));
  if (f.has("column_time_ns")) s.columnTimeNs = f.integer("column_time_ns");
  if (f.has("first_column_azimuth_deg"))
    s.firstColumnAzimuthDeg = f.number("first_column_azimuth_deg");
  if (f.has("spin")) {
    const std::string spin = f.text("spin");
    if (spin != "clockwise" && spin != "counterclockwise")
      throw Error(cat(f.where("spin"), ": '", spin,
                      "' is neither 'clockwise' nor 'counterclockwise'",
                      didYouMean(spin, {"clockwise", "counterclockwise"})));
    s.spin = spin == "clockwise" ? -1 : 1;
  }
  if (f.has("min_range_m")) s.minRange = f.number("min_range_m");
  if (f.has("max_range_m")) s.maxRange = f.number("max_range_m");
  if (f.has("sensor_from_lidar")) {
    s.sensorFromLidar = f.matrix("sensor_from_lidar");
    requireRigid(s.sensorFromLidar, f.where("sensor_from_lidar"));
  }
  if (f.has("pixel_shift_by_row")) {
    s.pixelShiftByRow.clear();
    for (int64_t v : f.integers("pixel_shift_by_row")) s.pixelShiftByRow.push_back(int(v));
  }
  if (f.has("column_window")) {
    const std::vector<int64_t> w = f.integers("column_window");
    if (w.size() != 2) throw Error(cat(f.where("column_window"), ": two measurement ids"));
    s.columnWindow = {int(w[0]), int(w[1])};
  } else if (!haveBase || s.source.format.rfind("ouster", 0) != 0) {
    s.columnWindow = {0, s.columns - 1};
  }
  if (f.has("pattern_period_s"))
    s.patternPeriodNs = std::llround(f.number("pattern_period_s") * 1e9);
  if (f.has("name"))
    s.name = f.text("name");
  else if (!haveBase)
    s.name = stemOf(source);
  return s;
}

// Every field valid, else an Error naming the source and the field.
void validate(LidarSensor& s) {
  const std::string& src = s.source.path;
  auto bad = [&](const std::string& field, const std::string& what) {
    return Error(cat(src, ": field '", field, "' ", what));
  };
  if (!(s.sweepRateHz > 0) || !std::isfinite(s.sweepRateHz) || s.sweepRateHz > 1e6)
    throw bad("sweep_rate_hz", cat("must be a positive rate in Hz, not ", s.sweepRateHz));
  if (!(s.minRange >= 0) || !std::isfinite(s.minRange))
    throw bad("min_range_m", cat("must be ≥ 0, not ", s.minRange));
  if (!(s.maxRange > s.minRange))
    throw bad("max_range_m", cat("must exceed min_range_m, not ", s.maxRange));
  const int64_t period = s.periodNs();
  if (s.kind == LidarKind::Spinning) {
    if (s.beams.empty()) throw bad("beams", "is empty");
    if (s.columns <= 0) throw bad("columns", cat("must be positive, not ", s.columns));
    if (s.columnTimeNs < 0) throw bad("column_time_ns", "must be ≥ 0");
    if (s.columnTimeNs > 0 && s.columnTimeNs * int64_t(s.columns) > period)
      throw bad("column_time_ns", cat(s.columnTimeNs, " ns times ", s.columns,
                                      " columns exceeds the sweep period (", period, " ns)"));
    for (size_t i = 0; i < s.beams.size(); ++i) {
      const LidarBeam& b = s.beams[i];
      if (!std::isfinite(b.elevationDeg) || std::fabs(b.elevationDeg) > 90)
        throw bad(cat("beams.elevation_deg[", i, "]"),
                  cat("must lie in [−90, 90], not ", b.elevationDeg));
      if (!std::isfinite(b.azimuthDeg))
        throw bad(cat("beams.azimuth_deg[", i, "]"), "is not finite");
      if (b.timeOffsetNs < 0 || b.timeOffsetNs >= period)
        throw bad(cat("beams.time_offset_ns[", i, "]"),
                  cat("must lie in [0, the period ", period, " ns), not ", b.timeOffsetNs));
      if (!std::isfinite(glm::dot(b.origin, b.origin)) || !std::isfinite(b.rangeOffset))
        throw bad(cat("beams.origin_m[", i, "]"), "is not finite");
    }
    if (!s.pixelShiftByRow.empty() && s.pixelShiftByRow.size() != s.beams.size())
      throw bad("pixel_shift_by_row",
                cat("has ", s.pixelShiftByRow.size(), " entries, the beam table ", s.beams.size()));
    for (int k = 0; k < 2; ++k)
      if (s.columnWindow[size_t(k)] < 0 || s.columnWindow[size_t(k)] >= s.columns)
        throw bad("column_window",
                  cat("ids must lie in [0, ", s.columns, "), not ", s.columnWindow[size_t(k)]));
    if (!std::isfinite(s.firstColumnAzimuthDeg))
      throw bad("first_column_azimuth_deg", "is not finite");
    if (s.spin != 1 && s.spin != -1) throw bad("spin", "must be ±1");
  } else {
    if (s.pattern.empty()) throw bad("pattern", "is empty");
    for (size_t i = 0; i < s.pattern.size(); ++i) {
      const PatternRay& r = s.pattern[i];
      if (r.timeNs < 0 || (i > 0 && r.timeNs < s.pattern[i - 1].timeNs))
        throw bad(cat("pattern[", i, "]"), "times must be ≥ 0 and not decrease");
      if (!std::isfinite(r.azimuthDeg) || !std::isfinite(r.elevationDeg) ||
          std::fabs(r.elevationDeg) > 90)
        throw bad(cat("pattern[", i, "]"), "has an angle out of range");
    }
    if (s.patternPeriodNs <= s.pattern.back().timeNs)
      throw bad("pattern_period_s", cat("must exceed the last ray's time (",
                                        formatTimeNs(s.pattern.back().timeNs), " s)"));
  }
  requireRigid(s.sensorFromLidar, cat(src, ": field 'sensor_from_lidar'"));
}

LidarSensor readAny(const std::string& text, const std::string& source, const std::string& dir) {
  LidarSensor s;
  if (looksLikeJson(text)) {
    const json doc = parseJson(text, source);
    if (isOusterJson(doc)) {
      s = readOuster(doc, source);
    } else {
      s = readApertureSpec(doc, source, dir);
    }
  } else {
    s = readVendorText(text, source);
    if (s.name == "velodyne" || s.name == "pattern") s.name = stemOf(source);
  }
  validate(s);
  return s;
}

}  // namespace

std::vector<std::string> lidarPresetNames() {
  std::vector<std::string> names;
  for (const auto& [name, text] : lidarPresetFiles()) names.push_back(name);
  return names;
}

const std::string& lidarPresetText(const std::string& name) {
  for (const auto& [preset, text] : lidarPresetFiles())
    if (preset == name) return text;
  const std::vector<std::string> names = lidarPresetNames();
  throw Error(cat("unknown LiDAR preset '", name, "'", didYouMean(name, names),
                  " (presets: ", join(names, ", "), "; or give a spec file)"));
}

LidarSensor loadLidarText(const std::string& text, const std::string& source) {
  return readAny(text, source, directoryOf(source));
}

LidarSensor loadLidar(const std::string& specOrPreset) {
  std::ifstream probe(specOrPreset, std::ios::binary);
  if (probe) return readAny(readText(specOrPreset), specOrPreset, directoryOf(specOrPreset));
  const auto& presets = lidarPresetFiles();
  const bool isPreset = std::any_of(presets.begin(), presets.end(),
                                    [&](const auto& p) { return p.first == specOrPreset; });
  if (!isPreset) {
    if (specOrPreset.find_first_of("/.") != std::string::npos)
      throw Error(cat(specOrPreset, ": cannot open the LiDAR spec"));
    lidarPresetText(specOrPreset);  // throws, with "did you mean"
  }
  LidarSensor s = readAny(lidarPresetText(specOrPreset), cat("preset ", specOrPreset), "");
  s.name = specOrPreset;
  s.source.format += " preset";
  return s;
}

}  // namespace aperture
