// Thin-lens camera: the perspective camera with a lens disk of radius R on the (U, V) plane
// at e, focused at depth f along −W. The ray code is PerspectiveCamera::rayAt.
#include <cmath>

#include "cameras/models.h"
#include "cameras/perspective.h"
#include "core/error.h"

namespace aperture {

namespace {

const ParamSpec kAperture{"aperture",
                          ParamKind::Number,
                          "scene units",
                          "Lens radius (0: pinhole)",
                          nullptr,
                          {0.0, std::nullopt},
                          {},
                          {},
                          {},
                          fieldAccess<&CameraParams::apertureRadius>()};
const ParamSpec kFocus{"focus",
                       ParamKind::Number,
                       "scene units",
                       "Distance of the in-focus plane along the view axis",
                       "|at - eye| with a look-at point, else 1",
                       {0.0, std::nullopt, true, false},
                       {},
                       {},
                       {},
                       fieldAccess<&CameraParams::focusDistance>()};

std::unique_ptr<CameraBase> makeThinLensCamera(const CameraParams& p,
                                               const glm::dvec3& renderOrigin) {
  return std::make_unique<PerspectiveCamera>(p, renderOrigin, "thinlens", p.apertureRadius,
                                             focusDistanceOf(p));
}

}  // namespace

const CameraModel& thinLensModel() {
  static const CameraModel m{"thinlens",
                             "perspective with a lens disk: depth of field, focused at `focus`",
                             makeThinLensCamera,
                             joinParamSpecs({commonParamSpecs(),
                                             {&distanceParamSpec(), &viewportParamSpec()},
                                             perspectiveParamSpecs(),
                                             {&kAperture, &kFocus}})};
  return m;
}

}  // namespace aperture
