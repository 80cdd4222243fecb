#include "cameras/registry.h"

#include "cameras/models.h"
#include "core/error.h"

namespace aperture {

namespace {
using Factory = std::unique_ptr<CameraBase> (*)(const CameraParams&, const glm::dvec3&);
struct Entry {
  const char* name;
  Factory make;
};
// Explicit registration: every model is listed here.
const Entry kCameras[] = {
    {"perspective", makePerspectiveCamera}, {"orthographic", makeOrthographicCamera},
    {"oblique", makeObliqueCamera},         {"thinlens", makeThinLensCamera},
    {"equirect", makeEquirectCamera},       {"fisheye", makeFisheyeCamera},
};
}  // namespace

std::vector<std::string> cameraTypeNames() {
  std::vector<std::string> names;
  for (const auto& e : kCameras) names.emplace_back(e.name);
  return names;
}

std::unique_ptr<Camera> makeCamera(const CameraParams& params, const glm::dvec3& renderOrigin) {
  return makeCameraModel(params, renderOrigin);
}

std::unique_ptr<CameraBase> makeCameraModel(const CameraParams& params,
                                            const glm::dvec3& renderOrigin) {
  for (const auto& e : kCameras)
    if (params.type == e.name) return e.make(params, renderOrigin);
  std::string known;
  for (const auto& e : kCameras) known += std::string(known.empty() ? "" : ", ") + e.name;
  throw Error(cat("unknown camera type '", params.type, "' (known: ", known, ")"));
}

}  // namespace aperture
