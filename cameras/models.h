#pragma once
// Factories of the individual camera models (one module each); see registry.cpp.
#include <memory>

#include "cameras/base.h"

namespace aperture {

std::unique_ptr<CameraBase> makePerspectiveCamera(const CameraParams& p,
                                                  const glm::dvec3& renderOrigin);
std::unique_ptr<CameraBase> makeOrthographicCamera(const CameraParams& p,
                                                   const glm::dvec3& renderOrigin);
std::unique_ptr<CameraBase> makeObliqueCamera(const CameraParams& p,
                                              const glm::dvec3& renderOrigin);
std::unique_ptr<CameraBase> makeThinLensCamera(const CameraParams& p,
                                               const glm::dvec3& renderOrigin);
std::unique_ptr<CameraBase> makeEquirectCamera(const CameraParams& p,
                                               const glm::dvec3& renderOrigin);
std::unique_ptr<CameraBase> makeFisheyeCamera(const CameraParams& p,
                                              const glm::dvec3& renderOrigin);

/// The common unit direction of an oblique camera (errors for a missing, zero, backwards or
/// too-steep direction: 89° or more from −W).
glm::dvec3 obliqueDirection(const CameraParams& p, const CameraFrame& frame);

}  // namespace aperture
