// Oblique parallel camera: origins as orthographic, one common direction that differs from
// −W, from a world direction or from two shear angles.
#include <cmath>

#include "cameras/models.h"
#include "cameras/parallel_projection.h"
#include "core/error.h"
#include "core/units.h"

namespace aperture {

glm::dvec3 obliqueDirection(const CameraParams& p, const CameraFrame& frame) {
  if (p.obliqueDir && p.obliqueAnglesDeg)
    throw Error("camera: give either --oblique-dir or --oblique-angles, not both");
  glm::dvec3 dir;
  if (p.obliqueDir) {
    requireFinite(*p.obliqueDir, "oblique direction");
    const double len = glm::length(*p.obliqueDir);
    if (!(len > 0)) throw Error("camera: the oblique direction is zero");
    dir = *p.obliqueDir / len;
  } else if (p.obliqueAnglesDeg) {
    // Shear angles: AX turns the direction towards +U, AY towards +V:
    // dir = normalize(−W + tan(AX)·U + tan(AY)·V).
    const glm::dvec2 a = *p.obliqueAnglesDeg;
    if (!std::isfinite(a.x) || !std::isfinite(a.y) || !(std::abs(a.x) < 89.0) ||
        !(std::abs(a.y) < 89.0))
      throw Error(cat("camera: oblique angles (", a.x, ",", a.y,
                      ") degrees must each be finite and below 89 in magnitude"));
    const glm::dvec3 g =
        -frame.w + std::tan(a.x * kRadPerDeg) * frame.u + std::tan(a.y * kRadPerDeg) * frame.v;
    dir = g / glm::length(g);
  } else {
    throw Error("camera: 'oblique' needs --oblique-dir X,Y,Z or --oblique-angles AX,AY");
  }
  const double angleDeg =
      std::atan2(glm::length(glm::cross(dir, -frame.w)), glm::dot(dir, -frame.w)) / kRadPerDeg;
  if (!(angleDeg < 89.0))
    throw Error(cat("camera: the oblique direction is ", angleDeg,
                    " degrees from the view direction; it must be less than 89"));
  return dir;
}

std::unique_ptr<CameraBase> makeObliqueCamera(const CameraParams& p,
                                              const glm::dvec3& renderOrigin) {
  const CameraFrame frame = frameFromParams(p);
  return std::make_unique<ParallelCamera>(p, renderOrigin, "oblique", obliqueDirection(p, frame));
}

}  // namespace aperture
