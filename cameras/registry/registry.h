#pragma once
// The camera models by name (explicit registration; see STYLE.md §4), each with the
// parameters it reads, and what needs a model by name: making a camera from parameters and
// resolving a user's parameters (cameras/registry/resolve.h).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cameras/geometry/view_volume.h"
#include "cameras/models/camera_model.h"
#include "cameras/registry/resolve.h"
#include "cameras/schema/params.h"
#include "core/engine/camera.h"

namespace aperture {

struct CalibratedView;

/// Every model, in registration order.
const std::vector<const CameraModel*>& cameraModels();
/// The model named `type`; throws Error listing the known ones (with "did you mean").
const CameraModel& findCameraModel(const std::string& type);
/// Known type names, in registration order.
std::vector<std::string> cameraTypeNames();

/// Builds the camera named by params.type. `renderOrigin` is the scene anchor: ray origins
/// are emitted relative to it (computed in double). Throws Error for an unknown type and for
/// bad parameters (checkCameraParamRanges, then the model's own checks: up parallel to the
/// view direction, zero vectors, ...).
std::unique_ptr<Camera> makeCamera(const CameraParams& params,
                                   const glm::dvec3& renderOrigin = glm::dvec3(0.0));

/// The same, with the model's full interface (scalar ray(), project(), viewVolume()).
std::unique_ptr<CameraBase> makeCameraModel(const CameraParams& params,
                                            const glm::dvec3& renderOrigin = glm::dvec3(0.0));

/// The view volume of the camera the parameters describe (builds it; errors as makeCamera).
ViewVolume viewVolumeFor(const CameraParams& params, double nearDist, double farDist);

/// calibratedViewOf (cameras/models/calibrated.h) for camera parameters: a calibrated camera's own
/// sensor and pose, read without building its table; a pinhole perspective camera's from its
/// description; nothing for the other models.
std::optional<CalibratedView> calibratedViewOf(const CameraParams& p);

}  // namespace aperture
