#pragma once
// The camera models by name (explicit registration; see STYLE.md §4), each with the
// parameters it reads.
#include <memory>
#include <string>
#include <vector>

#include "cameras/schema/param_schema.h"
#include "cameras/schema/params.h"
#include "core/engine/camera.h"

namespace aperture {

class CameraBase;

/// One registered model: its name, a one-line summary, its factory and every parameter it
/// reads (common ones included), as declared by its module.
struct CameraModel {
  const char* name;
  const char* summary;
  std::unique_ptr<CameraBase> (*make)(const CameraParams&, const glm::dvec3& renderOrigin);
  std::vector<const ParamSpec*> params;
  bool accepts(const std::string& paramName) const;
};

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

}  // namespace aperture
