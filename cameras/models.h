#pragma once
// Factories of the individual camera models (one module each); see registry.cpp.
#include <memory>

#include "cameras/base.h"

namespace aperture {

std::unique_ptr<Camera> makePerspectiveCamera(const CameraParams& p,
                                              const glm::dvec3& renderOrigin);

}  // namespace aperture
