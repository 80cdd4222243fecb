#include "cameras/registry/registry.h"

#include "cameras/models/calibrated.h"
#include "cameras/models/camera_models.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

const std::vector<const CameraModel*>& cameraModels() {
  // Explicit registration: every model is listed here.
  static const std::vector<const CameraModel*> models = {
      &perspectiveModel(), &orthographicModel(), &obliqueModel(),    &thinLensModel(),
      &equirectModel(),    &fisheyeModel(),      &calibratedModel(),
  };
  return models;
}

std::vector<std::string> cameraTypeNames() {
  std::vector<std::string> names;
  for (const CameraModel* m : cameraModels()) names.emplace_back(m->name);
  return names;
}

const CameraModel& findCameraModel(const std::string& type) {
  for (const CameraModel* m : cameraModels())
    if (type == m->name) return *m;
  throw Error(cat("unknown camera type '", type, "' (known: ", join(cameraTypeNames(), ", "), ")",
                  didYouMean(type, cameraTypeNames())));
}

std::unique_ptr<Camera> makeCamera(const CameraParams& params, const glm::dvec3& renderOrigin) {
  return makeCameraModel(params, renderOrigin);
}

std::unique_ptr<CameraBase> makeCameraModel(const CameraParams& params,
                                            const glm::dvec3& renderOrigin) {
  const CameraModel& model = findCameraModel(params.type);
  checkCameraParamRanges(params);
  return model.make(params, renderOrigin);
}

ViewVolume viewVolumeFor(const CameraParams& params, double nearDist, double farDist) {
  return makeCameraModel(params)->viewVolume(nearDist, farDist);
}

std::optional<CalibratedView> calibratedViewOf(const CameraParams& p) {
  if (p.type == "calibrated")
    return CalibratedView{calibratedSensorOf(p), calibratedWorldToCamera(p)};
  if (p.type != "perspective") return std::nullopt;
  return calibratedViewOf(makeCameraModel(p)->describe());
}

}  // namespace aperture
