#pragma once
// The camera models (one module each), each declared as a CameraModel; the registry
// (registry.cpp) lists them. The parameters CameraBase reads are declared in base.h.
#include <vector>

#include "cameras/models/base.h"
#include "cameras/models/camera_model.h"
#include "cameras/schema/param_schema.h"

namespace aperture {

const CameraModel& perspectiveModel();
const CameraModel& thinLensModel();
const CameraModel& orthographicModel();
const CameraModel& obliqueModel();
const CameraModel& equirectModel();
const CameraModel& fisheyeModel();
const CameraModel& calibratedModel();

/// The perspective window (perspectiveWindowParamSpecs) and clip: what the perspective and
/// thin-lens models read beside d and viewport (declared in base.cpp and
/// perspective.cpp).
const std::vector<const ParamSpec*>& perspectiveParamSpecs();

/// The common unit direction of an oblique camera (errors for a missing, zero, backwards or
/// too-steep direction: 89° or more from −W).
glm::dvec3 obliqueDirection(const CameraParams& p, const CameraFrame& frame);

}  // namespace aperture
