#pragma once
// One camera model as its module declares it: name, summary, factory and the parameters it
// reads. Each model module defines one (camera_models.h); the registry (registry.h) lists them.
#include <algorithm>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <vector>

#include "cameras/schema/param_schema.h"
#include "cameras/schema/params.h"

namespace aperture {

class CameraBase;

/// One model: its name, a one-line summary, its factory and every parameter it reads (common
/// ones included), as declared by its module.
struct CameraModel {
  const char* name;
  const char* summary;
  std::unique_ptr<CameraBase> (*make)(const CameraParams&, const glm::dvec3& renderOrigin);
  std::vector<const ParamSpec*> params;
  bool accepts(const std::string& paramName) const {
    return std::any_of(params.begin(), params.end(),
                       [&](const ParamSpec* s) { return paramName == s->name; });
  }
};

}  // namespace aperture
