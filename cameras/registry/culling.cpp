#include "cameras/registry/culling.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/util/error.h"

namespace aperture {

bool CameraCuller::mayIntersectBox(const glm::dvec3& lo, const glm::dvec3& hi) const {
  if (seesEverything) return true;
  const glm::dvec3 a = lo - pad, b = hi + pad;
  for (const ViewVolume& v : volumes)
    if (v.mayIntersectBox(a, b)) return true;
  return false;
}

WorldBoxTest CameraCuller::test() const {
  return [this](const glm::dvec3& lo, const glm::dvec3& hi) { return mayIntersectBox(lo, hi); };
}

CameraCuller cullerFor(const std::vector<CameraParams>& cameras, const glm::dvec3& renderOrigin) {
  if (cameras.empty()) throw Error("culling: no cameras");
  CameraCuller c;
  const double inf = std::numeric_limits<double>::infinity();
  for (const CameraParams& p : cameras) {
    const auto cam = makeCameraModel(p, renderOrigin);
    ViewVolume v = cam->viewVolume(0.0, inf);
    if (v.kind == ViewVolume::Kind::AllSpace) c.seesEverything = true;
    // Ray origins are e (+ a lens point, + a point of the viewport for parallel cameras)
    // relative to the render origin, rounded to float once: at most half an ulp of the
    // largest magnitude, bounded here by 2^-22 of a generous magnitude.
    const glm::dvec3 eye = cam->frame().e - renderOrigin;
    const double reach = std::max({std::abs(eye.x), std::abs(eye.y), std::abs(eye.z)}) +
                         std::abs(cam->vw()) + std::abs(cam->vh()) + std::abs(p.apertureRadius);
    c.pad = std::max(c.pad, reach * std::ldexp(1.0, -22));
    c.volumes.push_back(std::move(v));
  }
  return c;
}

}  // namespace aperture
