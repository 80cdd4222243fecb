#pragma once
// Maps camera type names to factories (explicit registration; see STYLE.md §4).
#include <memory>
#include <string>
#include <vector>

#include "cameras/params.h"
#include "core/camera.h"

namespace aperture {

/// Builds the camera named by params.type. `renderOrigin` is the scene anchor: ray origins
/// are emitted relative to it (computed in double). Throws Error for an unknown type (listing
/// the known ones) and for degenerate parameters (up parallel to the view direction, zero or
/// non-finite vectors, d <= 0, viewport <= 0, fov outside (0, 180), ...).
std::unique_ptr<Camera> makeCamera(const CameraParams& params,
                                   const glm::dvec3& renderOrigin = glm::dvec3(0.0));

class CameraBase;
/// The same, with the model's full interface (scalar ray(), project(), viewVolume()).
std::unique_ptr<CameraBase> makeCameraModel(const CameraParams& params,
                                            const glm::dvec3& renderOrigin = glm::dvec3(0.0));

/// Known type names, in registration order.
std::vector<std::string> cameraTypeNames();

}  // namespace aperture
