#include "apps/services/command_camera.h"

#include <algorithm>
#include <cmath>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"

namespace aperture::app {

CameraParams resolveCommandCamera(const ParamSet& given, const CameraParams& defaults,
                                  const glm::dvec3& lo, const glm::dvec3& hi) {
  CameraParams p = resolveCameraParams(given, defaults);
  if (p.worldToCamera || p.cameraToWorld) return p;  // posed by its matrix
  const glm::dvec3 centre = 0.5 * (lo + hi);
  if (given.has("eye")) {
    if (!p.at && !p.dir) p.at = centre;
    return p;
  }
  // Frame the scene: look at its centre from above-front, far enough for the bounding
  // sphere to fit the vertical field of view.
  const double radius = std::max(0.5 * glm::length(hi - lo), 1e-6);
  const double halfFov =
      0.5 * p.fovDeg.value_or(fovParamSpec().defaultAs<double>()) * 3.14159265358979323846 / 180.0;
  const glm::dvec3 view =
      p.dir ? glm::normalize(*p.dir) : glm::normalize(glm::dvec3(-0.35, -0.45, -1.0));
  const glm::dvec3 target = p.at.value_or(centre);
  p.eye = target - view * (0.8 * radius / std::sin(halfFov));
  if (!p.dir) p.at = target;
  return p;
}

LoadedScene loadSceneForCamera(const Device& device, const SceneOptions& scene,
                               const ParamSet& given, const CameraParams& defaults, bool quiet,
                               CameraParams& camera) {
  const SceneSpec spec = scene.spec();
  LoadedScene loaded = loadSceneMeshes(spec, quiet);
  camera = resolveCommandCamera(given, defaults, loaded.worldLo, loaded.worldHi);
  buildLoadedScene(device, loaded, spec, quiet, {camera});
  return loaded;
}

}  // namespace aperture::app
