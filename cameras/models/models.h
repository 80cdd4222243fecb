#pragma once
// The camera models (one module each) and the parameter declarations they share; the
// registry (registry.cpp) lists the models.
#include <initializer_list>
#include <memory>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/param_schema.h"

namespace aperture {

const CameraModel& perspectiveModel();
const CameraModel& thinLensModel();
const CameraModel& orthographicModel();
const CameraModel& obliqueModel();
const CameraModel& equirectModel();
const CameraModel& fisheyeModel();
const CameraModel& calibratedModel();

/// type, size, spp, eye, at, dir, up: read by every model (declared in base.cpp).
const std::vector<const ParamSpec*>& commonParamSpecs();
/// The image-plane window of the planar models: d and viewport (declared in base.cpp).
const ParamSpec& distanceParamSpec();
const ParamSpec& viewportParamSpec();
/// fov, fov_axis, focal_length, sensor, sensor_fit, shift, blender_shift, architectural, clip
/// (declared in perspective.cpp).
const std::vector<const ParamSpec*>& perspectiveParamSpecs();

/// The concatenation of spec lists (a model's parameters from shared groups).
std::vector<const ParamSpec*> joinParamSpecs(
    std::initializer_list<std::vector<const ParamSpec*>> groups);

/// The common unit direction of an oblique camera (errors for a missing, zero, backwards or
/// too-steep direction: 89° or more from −W).
glm::dvec3 obliqueDirection(const CameraParams& p, const CameraFrame& frame);

}  // namespace aperture
