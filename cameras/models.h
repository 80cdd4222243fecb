#pragma once
// The camera models (one module each), each declared as a CameraModel; the registry
// (registry.cpp) lists them. The parameters CameraBase reads are declared in base.h.
#include <vector>

#include "cameras/base.h"
#include "cameras/camera_model.h"
#include "cameras/param_schema.h"

namespace aperture {

const CameraModel& perspectiveModel();
const CameraModel& thinLensModel();
const CameraModel& orthographicModel();
const CameraModel& obliqueModel();
const CameraModel& equirectModel();
const CameraModel& fisheyeModel();
const CameraModel& calibratedModel();

/// fov, fov_axis, focal_length, sensor, sensor_fit, shift, blender_shift, architectural, clip
/// (declared in perspective.cpp).
const std::vector<const ParamSpec*>& perspectiveParamSpecs();

/// The common unit direction of an oblique camera (errors for a missing, zero, backwards or
/// too-steep direction: 89° or more from −W).
glm::dvec3 obliqueDirection(const CameraParams& p, const CameraFrame& frame);

}  // namespace aperture
