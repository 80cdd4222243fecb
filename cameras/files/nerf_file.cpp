// transforms.json: nerfstudio's (nerfstudio/data/dataparsers/nerfstudio_dataparser.py) and the
// original NeRF / instant-ngp one.
//
//   frames[]        file_path (the image, relative to the json's folder; NeRF's synthetic
//                   scenes leave out the extension) and transform_matrix: camera-to-world,
//                   4×4 row-major, OpenGL camera axes (x right, y up, z backwards).
//   intrinsics      nerfstudio: fl_x fl_y cx cy w h in pixels, half-integer pixel centres
//                   (its rays leave pixel (i, j) through (j + ½, i + ½)). NeRF / instant-ngp:
//                   camera_angle_x (and camera_angle_y) in radians, the full field of view:
//                   fx = w / 2 / tan(camera_angle_x / 2), fy likewise from camera_angle_y or
//                   fy = fx; cx = w / 2 and cy = h / 2 unless given.
//   distortion      k1 k2 k3 k4 p1 p2 with `camera_model` OPENCV (and the other perspective
//                   names nerfstudio accepts) or OPENCV_FISHEYE; PINHOLE when absent.
//
// Where a key sits, as nerfstudio reads it: a key at the top level applies to every frame
// (a frame's own value is then ignored, as nerfstudio ignores it); a key absent at the top
// level is read from each frame. The distortion coefficients go together: when any of k1 k2 k3
// p1 p2 is at the top level, all six come from there. `camera_model` is top-level in
// nerfstudio; a frame may repeat it with another model of the same kind (perspective or
// fisheye), which nerfstudio ignores and this reader uses (the writer does so for files with
// several sensors). The image size, when neither the top level nor the frame gives it, is
// read from the image file (trying .png .jpg .jpeg .exr after a path without extension).
// `applied_transform` (what ns-process-data did to COLMAP's world) is not applied: poses are
// in the file's own world.
//
// The coefficients onto COLMAP's models (nerfstudio's camera_utils.py): perspective
// distortion is x_d = x·(1 + k1 r² + k2 r⁴ + k3 r⁶ + k4 r⁸) + 2 p1 x y + p2 (r² + 2x²) and
// y_d likewise with p1 and p2 exchanged: OpenCV's tangential terms. COLMAP's OPENCV is this
// with k3 = k4 = 0; FULL_OPENCV's radial factor (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴
// + k6 r⁶) is it with its k4 = k5 = k6 = 0, so nerfstudio's k3 is FULL_OPENCV's k3. No COLMAP
// model has the r⁸ term: k4 ≠ 0 is refused. Fisheye distortion is θ_d = θ(1 + k1θ² + k2θ⁴ +
// k3θ⁶ + k4θ⁸), COLMAP's OPENCV_FISHEYE, which has no tangential terms: p1, p2 ≠ 0 are
// refused there.
//
// Values read back bit-exact through the writer, except the translation of a pose: the file
// holds camera-to-world, and inverting a rigid transform twice rounds its translation (the
// rotation part is exact).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "cameras/files/camera_file_formats.h"
#include "core/io/atomic_file.h"
#include "core/io/image_codec.h"
#include "core/util/error.h"
#include "core/util/spelling.h"
#include "core/util/units.h"

namespace aperture::camera_files {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The camera_model names nerfstudio accepts that map onto COLMAP's models: the rows' nerfstudio
// spellings, in the table's order.
std::vector<std::string> nerfModelNames() {
  std::vector<std::string> names;
  for (const LensModelInfo& m : lensModels())
    if (m.nerfstudio.expressible() &&
        std::find(names.begin(), names.end(), m.nerfstudio.name) == names.end())
      names.emplace_back(m.nerfstudio.name);
  return names;
}

// Whether nerfstudio's camera_model `name` is a fisheye: whether the models it spells are.
bool isFisheyeName(const std::string& name) {
  for (const LensModelInfo& m : lensModels())
    if (m.nerfstudio.expressible() && name == m.nerfstudio.name) return m.fisheye;
  return false;
}

// The intrinsics of one frame as the file gives them.
struct NerfIntrinsics {
  std::string model;  ///< camera_model, "" when absent
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  double k[4] = {0, 0, 0, 0};
  double p[2] = {0, 0};
};

const json* keyOf(const json& doc, const json& frame, const char* key) {
  if (doc.contains(key)) return &doc[key];
  if (frame.is_object() && frame.contains(key)) return &frame[key];
  return nullptr;
}

// The size of the image at `path` (tried with the usual extensions when it has none).
std::optional<glm::ivec2> imageFileSize(const fs::path& path) {
  std::vector<fs::path> candidates = {path};
  if (!path.has_extension())
    for (const char* ext : {".png", ".jpg", ".jpeg", ".exr"})
      candidates.push_back(fs::path(path).concat(ext));
  for (const fs::path& p : candidates) {
    std::error_code ec;
    // Never a device, a folder or a /proc file (size 0), which could block a read.
    if (!fs::is_regular_file(p, ec) || fs::file_size(p, ec) == 0 || ec) continue;
    ImageFileInfo info;
    std::string error;
    if (!imageCodec().read(p.string(), SampleType::UInt8, info, nullptr, error)) continue;
    return glm::ivec2(info.width, info.height);
  }
  return std::nullopt;
}

NerfIntrinsics frameIntrinsics(const json& doc, const json& frame, bool angles,
                               const fs::path& folder, const std::string& fileName,
                               const std::string& context) {
  NerfIntrinsics in;
  // camera_model: the frame's own (an extension nerfstudio ignores) or the top level's.
  const json* m = frame.contains("camera_model") ? &frame["camera_model"]
                  : doc.contains("camera_model") ? &doc["camera_model"]
                                                 : nullptr;
  if (m) {
    if (!m->is_string())
      throw Error(cat(context, ": camera_model must be a string, got ", shown(*m)));
    in.model = m->get<std::string>();
    const std::vector<std::string> names = nerfModelNames();
    if (std::find(names.begin(), names.end(), in.model) == names.end())
      throw Error(cat(context, ": camera_model '", in.model, "' is not supported (supported: ",
                      join(names, ", "), ")", didYouMean(in.model, names)));
    const json& top = doc.contains("camera_model") ? doc["camera_model"] : *m;
    if (!top.is_string() || isFisheyeName(top.get<std::string>()) != isFisheyeName(in.model))
      throw Error(cat(context, ": camera_model '", in.model, "' and the top level's ", shown(top),
                      " differ in kind (perspective or fisheye); nerfstudio uses the top level's"));
  }

  const json* w = keyOf(doc, frame, "w");
  const json* h = keyOf(doc, frame, "h");
  if (w) in.width = imageSide(*w, context + " w");
  if (h) in.height = imageSide(*h, context + " h");
  if (!w || !h) {
    const auto size = imageFileSize(folder / fileName);
    if (!size)
      throw Error(cat(context, ": no image size (w, h) in the file, and the image '",
                      (folder / fileName).string(),
                      "' (or with .png .jpg .jpeg .exr) cannot be read"));
    if (!w) in.width = size->x;
    if (!h) in.height = size->y;
  }

  if (angles) {
    const json* ax = keyOf(doc, frame, "camera_angle_x");
    if (!ax) throw Error(cat(context, ": neither fl_x nor camera_angle_x is given"));
    const auto focalOfAngle = [&](const json& angle, int side, const char* key) {
      const double a = finiteNumber(angle, cat(context, " ", key));
      if (!(a > 0 && a < kPi))
        throw Error(cat(context, ": ", key, " ", a, " must be a field of view in (0, π) radians"));
      return side / 2.0 / std::tan(a / 2);
    };
    in.fx = focalOfAngle(*ax, in.width, "camera_angle_x");
    const json* ay = keyOf(doc, frame, "camera_angle_y");
    in.fy = ay ? focalOfAngle(*ay, in.height, "camera_angle_y") : in.fx;
  } else {
    const json* fx = keyOf(doc, frame, "fl_x");
    if (!fx) throw Error(cat(context, ": no focal length (fl_x)"));
    in.fx = finiteNumber(*fx, context + " fl_x");
    const json* fy = keyOf(doc, frame, "fl_y");
    in.fy = fy ? finiteNumber(*fy, context + " fl_y") : in.fx;
  }
  const json* cx = keyOf(doc, frame, "cx");
  const json* cy = keyOf(doc, frame, "cy");
  in.cx = cx ? finiteNumber(*cx, context + " cx") : in.width / 2.0;
  in.cy = cy ? finiteNumber(*cy, context + " cy") : in.height / 2.0;

  bool distortionAtTop = false;
  for (const char* key : {"k1", "k2", "k3", "p1", "p2"}) distortionAtTop |= doc.contains(key);
  const json& source = distortionAtTop ? doc : frame;
  const char* names[] = {"k1", "k2", "k3", "k4", "p1", "p2"};
  for (int i = 0; i < 6; ++i) {
    if (!source.contains(names[i])) continue;
    const double v = finiteNumber(source[names[i]], cat(context, " ", names[i]));
    (i < 4 ? in.k[i] : in.p[i - 4]) = v;
  }
  return in;
}

// The named model when it holds the values, else the first model, in the table's order, of the
// named model's kind (perspective or fisheye) with two focal lengths that holds them (nerfstudio
// has one camera_model for several of COLMAP's: OPENCV for OPENCV and FULL_OPENCV).
Lens nerfLens(const NerfIntrinsics& in, const std::string& context) {
  const std::vector<double> values = {in.k[0], in.k[1], in.k[2], in.k[3], in.p[0], in.p[1]};
  const std::vector<double> intrinsics = {in.fx, in.fy, in.cx, in.cy};
  const bool fisheye = isFisheyeName(in.model);
  const auto holding = [&](const LensModelInfo& m) {
    return withContext(context, [&] { return lensOfSlots(m, intrinsics, m.nerfstudio, values); });
  };
  for (const LensModelInfo& m : lensModels())
    if (m.nerfstudio.expressible() && in.model == m.name)
      if (const auto lens = holding(m)) return *lens;
  for (const LensModelInfo& m : lensModels())
    if (m.nerfstudio.expressible() && m.fisheye == fisheye && !m.singleFocal())
      if (const auto lens = holding(m)) return *lens;
  // Nothing holds them: nerfstudio's perspective k4 multiplies r⁸, which no COLMAP model has
  // (FULL_OPENCV's k4 is a denominator term); COLMAP's OPENCV_FISHEYE has no p1, p2.
  const char* names[] = {"k1", "k2", "k3", "k4", "p1", "p2"};
  std::vector<std::string> given;
  for (size_t i = 0; i < values.size(); ++i)
    if (values[i] != 0) given.push_back(cat(names[i], " = ", values[i]));
  throw Error(cat(context, ": ", in.model.empty() ? "PINHOLE" : in.model, " with ",
                  join(given, ", "), ": no COLMAP model of nerfstudio's ",
                  fisheye ? "fisheye" : "perspective", " camera models holds them"));
}

bool anyFrameHas(const json& frames, const char* key) {
  for (const json& f : frames)
    if (f.is_object() && f.contains(key)) return true;
  return false;
}

// ---- writing ----

// A sensor as nerfstudio keys (half-integer pixel centres).
struct NerfSensor {
  std::string model;
  double fx, fy, cx, cy;
  int width, height;
  std::vector<double> k;  ///< k1 k2 k3 k4
  std::vector<double> p;  ///< p1 p2 (perspective only)
};

NerfSensor nerfSensor(const CalibratedSensor& sensor, const std::string& context) {
  const CalibratedSensor s = inPixelCentre(sensor, PixelCentre::HalfInteger);
  const Lens& lens = s.lens;
  const LensSpelling& spelling = lens.info().nerfstudio;
  if (!spelling.expressible())
    throw Error(cat(context, ": ", lens.info().name, " has no nerfstudio camera_model"));
  const std::optional<std::vector<double>> values = slotValues(spelling, lens.distortion());
  if (!values) {
    std::vector<std::string> left;
    const std::vector<double> d = lens.distortion();
    for (size_t j = 0; j < d.size(); ++j)
      if (d[j] != 0 &&
          std::find(spelling.slots.begin(), spelling.slots.end(), int(j)) == spelling.slots.end())
        left.push_back(cat(lens.info().paramNames[lens.info().intrinsicCount() + j], " = ", d[j]));
    throw Error(cat(context, ": ", lens.info().name, " with ", join(left, ", "), ": nerfstudio's ",
                    spelling.name, " has no slot for them (only 0 can be written)"));
  }
  NerfSensor n{spelling.name,
               lens.fx(),
               lens.fy(),
               lens.cx(),
               lens.cy(),
               s.width,
               s.height,
               {values->begin(), values->begin() + 4},
               {}};
  if (values->size() > 4) n.p = {(*values)[4], (*values)[5]};
  return n;
}

void putIntrinsics(json& j, const NerfSensor& n) {
  j["fl_x"] = n.fx;
  j["fl_y"] = n.fy;
  j["cx"] = n.cx;
  j["cy"] = n.cy;
  j["w"] = n.width;
  j["h"] = n.height;
  const char* kNames[] = {"k1", "k2", "k3", "k4"};
  for (int i = 0; i < 4; ++i) j[kNames[i]] = n.k[size_t(i)];
  if (!n.p.empty()) {
    j["p1"] = n.p[0];
    j["p2"] = n.p[1];
  }
}

}  // namespace

CameraFile readNerfJson(const std::string& path, const json& doc) {
  const json& frames = doc["frames"];
  if (!frames.is_array() || frames.empty())
    throw Error(cat(path, ": 'frames' must be a non-empty list"));
  CameraFile file;
  file.path = path;
  const bool nerfstudio = doc.contains("fl_x") || anyFrameHas(frames, "fl_x");
  file.format = nerfstudio ? CameraFileFormat::Nerfstudio : CameraFileFormat::InstantNgp;
  const fs::path folder = fs::path(path).parent_path();
  std::map<std::string, size_t> frameOfName;
  for (size_t i = 0; i < frames.size(); ++i) {
    const json& frame = frames[i];
    std::string context = cat(path, ": frame ", i);
    if (!frame.is_object()) throw Error(cat(context, ": expected an object, got ", shown(frame)));
    if (!frame.contains("file_path") || !frame["file_path"].is_string())
      throw Error(cat(context, ": needs a file_path (a string)"));
    const std::string name = frame["file_path"].get<std::string>();
    context += cat(" ('", name, "')");
    if (!frameOfName.emplace(name, i).second)
      throw Error(cat(context, ": file_path '", name, "' is given twice (also frame ",
                      frameOfName[name], ")"));
    const NerfIntrinsics in = frameIntrinsics(doc, frame, !nerfstudio, folder, name, context);
    const CalibratedSensor sensor{in.width, in.height, nerfLens(in, context),
                                  PixelCentre::HalfInteger};
    if (!frame.contains("transform_matrix"))
      throw Error(cat(context, ": needs a transform_matrix (camera-to-world, 4×4)"));
    const glm::dmat4 cameraToWorld =
        dmat4FromJson(frame["transform_matrix"], context + " transform_matrix");
    file.images.push_back({name, shareSensor(file, sensor),
                           worldToCameraOpenCV(cameraToWorld, AxisConvention::OpenGL, true,
                                               context + " transform_matrix")});
  }
  return file;
}

}  // namespace aperture::camera_files

namespace aperture {

namespace fs = std::filesystem;
using nlohmann::json;

void writeNerfstudioJson(const CameraFile& file, const std::string& path) {
  using camera_files::NerfSensor;
  const auto label = [&](size_t s) {
    return s < file.sensorIds.size() ? file.sensorIds[s] : std::to_string(s + 1);
  };
  std::vector<NerfSensor> sensors;
  for (size_t s = 0; s < file.sensors.size(); ++s)
    sensors.push_back(camera_files::nerfSensor(file.sensors[s], cat(path, ": sensor ", label(s))));
  std::vector<int> used;
  for (const CalibratedImage& im : file.images) {
    if (im.sensor < 0 || size_t(im.sensor) >= sensors.size())
      throw Error(
          cat(path, ": image '", im.name, "': sensor index ", im.sensor, " is out of range"));
    if (std::find(used.begin(), used.end(), im.sensor) == used.end()) used.push_back(im.sensor);
  }
  json doc = json::object();
  if (!used.empty()) {
    const NerfSensor& first = sensors[size_t(used[0])];
    bool sameModel = true;
    for (int s : used) {
      if (camera_files::isFisheyeName(sensors[size_t(s)].model) !=
          camera_files::isFisheyeName(first.model))
        throw Error(cat(path, ": nerfstudio has one camera_model per file; sensors ",
                        label(size_t(used[0])), " and ", label(size_t(s)),
                        " are of different kinds (perspective and fisheye)"));
      sameModel &= sensors[size_t(s)].model == first.model;
    }
    doc["camera_model"] = first.model;
    if (used.size() == 1) camera_files::putIntrinsics(doc, first);
    json frames = json::array();
    for (const CalibratedImage& im : file.images) {
      json f;
      f["file_path"] = im.name;
      f["transform_matrix"] = camera_files::rowMajorJson(
          poseInConvention(im.worldToCamera, AxisConvention::OpenGL, true));
      if (used.size() > 1) {
        if (!sameModel) f["camera_model"] = sensors[size_t(im.sensor)].model;
        camera_files::putIntrinsics(f, sensors[size_t(im.sensor)]);
      }
      frames.push_back(std::move(f));
    }
    doc["frames"] = std::move(frames);
  } else {
    doc["frames"] = json::array();
  }
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
  writeTextAtomically(path, camera_files::jsonFileText(doc, path));
}

}  // namespace aperture
