// aperture.Camera and aperture.load_cameras. Keyword arguments take the road of a job file's
// camera entry: each becomes a JSON value read by paramFromJson (apps/jobs/job_camera.cpp) against
// the camera parameter schema, then resolveCameraParams checks the set (types, ranges,
// conflicts, companions) with messages naming "Camera(fov=...)".
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <optional>
#include <variant>

#include "apps/jobs/job_camera.h"
#include "apps/jobs/job_json.h"
#include "apps/services/camera_file_params.h"
#include "bindings.h"
#include "cameras/files/camera_file.h"
#include "cameras/registry/describe.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/param_schema.h"
#include "core/util/error.h"
#include "core/util/spelling.h"
#include "file_errors.h"

namespace aperture::python {

namespace {

using app::json;

/// A Python value as JSON: bool, int, float, str, and sequences of them (tuples, lists,
/// NumPy arrays through tolist()). Anything else is an Error naming `where`.
json jsonOf(nb::handle v, const std::string& where) {
  if (nb::isinstance<nb::bool_>(v)) return nb::cast<bool>(v);
  if (nb::isinstance<nb::int_>(v)) return nb::cast<long long>(v);
  if (nb::isinstance<nb::float_>(v)) return nb::cast<double>(v);
  if (nb::isinstance<nb::str>(v)) return nb::cast<std::string>(v);
  if (nb::hasattr(v, "tolist")) return jsonOf(v.attr("tolist")(), where);  // NumPy
  if (nb::isinstance<nb::list>(v) || nb::isinstance<nb::tuple>(v)) {
    json a = json::array();
    for (nb::handle item : v) a.push_back(jsonOf(item, where));
    return a;
  }
  throw Error(cat(where, ": cannot use a value of Python type '",
                  nb::cast<std::string>(nb::type_name(v.type())), "'"));
}

/// The keyword names Camera() accepts: the schema's parameter names.
std::vector<std::string> keywordNames() {
  std::vector<std::string> names;
  for (const ParamSpec* s : allCameraParamSpecs()) names.emplace_back(s->name);
  return names;
}

/// The parameters given as keywords, each read through the job file's paramFromJson with
/// the source "Camera(NAME=...)"; an unknown keyword is an Error with "did you mean".
ParamSet paramsOfKeywords(const nb::dict& kwargs) {
  json entry = json::object();
  std::vector<std::string> order;  // the keywords as given (JSON objects sort their keys)
  for (auto [key, value] : kwargs) {
    const std::string name = nb::cast<std::string>(key);
    order.push_back(name);
    if (!findCameraParamSpec(name))
      throw Error(cat("Camera(): unknown parameter '", name, "'", didYouMean(name, keywordNames()),
                      " (see aperture.camera_parameters())"));
    entry[name] = jsonOf(value, cat("Camera(", name, "=...)"));
  }
  // Object's file and path make paramFromJson's messages read "Camera(): fov: ...".
  const std::string file = "Camera()";  // Object keeps a reference to its file's name
  const app::Object object(file, "", entry, keywordNames());
  ParamSet given;
  for (const std::string& name : order) {
    const ParamSpec& spec = *findCameraParamSpec(name);
    given.set(spec, app::paramFromJson(object, spec, entry[name]), cat("Camera(", name, "=...)"));
  }
  return given;
}

/// A ParamValue as the Python value a keyword takes back.
nb::object pythonOf(const ParamValue& v) {
  return std::visit(
      [](const auto& x) -> nb::object {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, glm::dvec2>)
          return nb::make_tuple(x.x, x.y);
        else if constexpr (std::is_same_v<T, glm::dvec3>)
          return nb::make_tuple(x.x, x.y, x.z);
        else if constexpr (std::is_same_v<T, glm::ivec2>)
          return nb::make_tuple(x.x, x.y);
        else if constexpr (std::is_same_v<T, std::vector<double>>) {
          nb::list l;
          for (double d : x) l.append(d);
          return std::move(l);
        } else
          return nb::cast(x);
      },
      v);
}

PyCamera cameraOfKeywords(const nb::dict& kwargs) {
  PyCamera c;
  c.params = resolveCameraParams(paramsOfKeywords(kwargs));
  makeCamera(c.params);  // the model's own checks (up parallel to the view, ...), now
  return c;
}

/// Camera.params: the parameters that differ from the defaults (and the type), by keyword.
nb::dict paramsOf(const PyCamera& c) {
  nb::dict d;
  const ParamSet given = paramSetOf(c.params, "");
  for (const ParamSet::Entry& e : given.entries()) d[e.spec->name] = pythonOf(e.value);
  return d;
}

/// What a Camera pickles as: its keywords (Camera.params) and its name, so that unpickling is
/// Camera(**params) again, through every check of the schema.
nb::tuple pickledState(const PyCamera& c) { return nb::make_tuple(paramsOf(c), c.name); }

void restoreState(PyCamera* self, const nb::tuple& state) {
  if (state.size() != 2) throw nb::value_error("Camera.__setstate__: expected (params, name)");
  new (self) PyCamera(cameraOfKeywords(nb::cast<nb::dict>(state[0])));
  self->name = nb::cast<std::string>(state[1]);
}

std::vector<PyCamera> loadCameras(const std::string& path,
                                  const std::optional<std::vector<std::string>>& images,
                                  std::optional<int> width, std::optional<int> height,
                                  std::optional<int> gltfScene) {
  CameraFileOptions options;
  options.gltfScene = gltfScene;
  std::optional<CameraFile> file;
  readingFiles({path}, [&] { file = readCameraFile(path, options); });
  app::GltfImageSize size;
  size.width = width;
  size.height = height;
  std::vector<PyCamera> cameras;
  for (const CalibratedImage* image :
       app::selectImages(*file, images.value_or(std::vector<std::string>{}), "images"))
    cameras.push_back({resolveCameraParams(app::imageParamSet(*file, *image, size)), image->name});
  return cameras;
}

}  // namespace

void bindCamera(nb::module_& m) {
  nb::class_<PyCamera>(m, "Camera",
                       "A camera: any model and parameter of the command line, checked by the "
                       "same schema (see `aperture camera --params-table`).")
      .def(
          "__init__",
          [](PyCamera* self, const nb::kwargs& kwargs) {
            new (self) PyCamera(cameraOfKeywords(kwargs));
          },
          "Camera(type='perspective', **params): keywords are the job file's camera keys "
          "(fov, size, eye, at, up, intrinsics, ...), checked by name and value.")
      .def_prop_ro("params", &paramsOf,
                   "The parameters that differ from the defaults (and type): Camera(**cam.params) "
                   "is the same camera.")
      .def("__getstate__", &pickledState)
      .def("__setstate__", &restoreState)
      .def_prop_ro(
          "width", [](const PyCamera& c) { return c.params.width; }, "Image width, pixels")
      .def_prop_ro(
          "height", [](const PyCamera& c) { return c.params.height; }, "Image height, pixels")
      .def_prop_ro(
          "type", [](const PyCamera& c) { return c.params.type; }, "The camera model")
      .def_prop_ro(
          "spp", [](const PyCamera& c) { return c.params.spp; }, "Samples per pixel")
      .def_rw("name", &PyCamera::name, "The image name (load_cameras), else ''")
      .def(
          "describe", [](const PyCamera& c) { return describeCamera(c.params); },
          "The text of `aperture camera --describe` for this camera.")
      .def("__repr__", [](const PyCamera& c) {
        std::string s = "Camera(";
        bool first = true;
        const ParamSet given = paramSetOf(c.params, "");
        for (const ParamSet::Entry& e : given.entries()) {
          s += cat(first ? "" : ", ", e.spec->name, "=",
                   nb::cast<std::string>(nb::repr(pythonOf(e.value))));
          first = false;
        }
        return s + ")";
      });

  m.def("load_cameras", &loadCameras, nb::arg("path"), nb::arg("images") = nb::none(),
        nb::arg("width") = nb::none(), nb::arg("height") = nb::none(),
        nb::arg("gltf_scene") = nb::none(),
        "The cameras of a camera file (COLMAP model folder, transforms.json, OpenCV JSON/YAML, "
        "glTF camera nodes), each with .name, in the file's order or in the order `images` "
        "names them; width / height: the image size of glTF cameras.");
  m.def("camera_parameters", &keywordNames, "The keyword names Camera() accepts.");
  m.def("camera_types", &cameraTypeNames, "The camera models Camera(type=...) accepts.");
}

}  // namespace aperture::python
