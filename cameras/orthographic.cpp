// Orthographic camera: parallel rays along −W from origins e + u·U + v·V on the image plane.
#include "cameras/models.h"
#include "cameras/parallel_projection.h"

namespace aperture {

std::unique_ptr<CameraBase> makeOrthographicCamera(const CameraParams& p,
                                                   const glm::dvec3& renderOrigin) {
  const CameraFrame frame = frameFromParams(p);
  return std::make_unique<ParallelCamera>(p, renderOrigin, "orthographic", -frame.w);
}

}  // namespace aperture
