// Thin-lens camera: the perspective camera with a lens disk of radius R on the (U, V) plane
// at e, focused at depth f along −W. The ray code is PerspectiveCamera::rayAt.
#include <cmath>

#include "cameras/models.h"
#include "cameras/perspective.h"
#include "core/error.h"

namespace aperture {

std::unique_ptr<CameraBase> makeThinLensCamera(const CameraParams& p,
                                               const glm::dvec3& renderOrigin) {
  requireFinite(p.apertureRadius, "aperture radius");
  requireFinite(p.focusDistance, "focus distance");
  if (!(p.apertureRadius >= 0))
    throw Error(cat("camera: aperture radius ", p.apertureRadius, " must be >= 0"));
  if (!(p.focusDistance > 0))
    throw Error(cat("camera: focus distance ", p.focusDistance, " must be > 0"));
  return std::make_unique<PerspectiveCamera>(p, renderOrigin, "thinlens", p.apertureRadius,
                                             p.focusDistance);
}

}  // namespace aperture
