// Orthographic camera: parallel rays along −W from origins e + u·U + v·V on the image plane.
#include "cameras/models/camera_models.h"
#include "cameras/models/parallel_projection.h"

namespace aperture {

namespace {
std::unique_ptr<CameraBase> makeOrthographicCamera(const CameraParams& p,
                                                   const glm::dvec3& renderOrigin) {
  const CameraFrame frame = frameFromParams(p);
  return std::make_unique<ParallelCamera>(p, renderOrigin, "orthographic", -frame.w);
}
}  // namespace

const CameraModel& orthographicModel() {
  static const CameraModel m{"orthographic", "parallel rays along the view axis",
                             makeOrthographicCamera,
                             joinParamSpecs({commonParamSpecs(), {&viewportParamSpec()}})};
  return m;
}

}  // namespace aperture
