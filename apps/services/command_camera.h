#pragma once
// The camera of a command (render, bench, camera, tradeoff, visibility): the parameters given,
// over the command's defaults, framed on the scene when no eye was given.
#include <glm/glm.hpp>

#include "apps/services/scene_setup.h"
#include "cameras/schema/param_schema.h"

namespace aperture::app {

/// The camera of a command: `given` over `defaults`, checked by the schema. With no --eye it
/// frames the world box [lo, hi] (looks at the centre from above and in front, far enough
/// for the bounding sphere to fill 80% of the vertical field of view); with --eye but neither
/// --at nor --dir it looks at the box's centre. Throws Error naming the flags.
CameraParams resolveCommandCamera(const ParamSet& given, const CameraParams& defaults,
                                  const glm::dvec3& lo, const glm::dvec3& hi);

/// A command's scene and camera: loads the meshes, frames the command-line camera on their
/// bounds (resolveCommandCamera) and builds the BVH (culled for that camera with --cull).
LoadedScene loadSceneForCamera(const Device& device, const SceneOptions& scene,
                               const ParamSet& given, const CameraParams& defaults, bool quiet,
                               CameraParams& camera);

}  // namespace aperture::app
