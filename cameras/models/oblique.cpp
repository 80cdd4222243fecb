// Oblique parallel camera: origins as orthographic, one common direction that differs from
// −W, from a world direction or from two shear angles.
#include <cmath>

#include "cameras/models/camera_models.h"
#include "cameras/models/parallel_projection.h"
#include "core/util/error.h"
#include "core/util/units.h"

namespace aperture {

glm::dvec3 obliqueDirection(const CameraParams& p, const CameraFrame& frame) {
  glm::dvec3 dir;
  if (p.obliqueDir) {
    requireFinite(*p.obliqueDir, "oblique direction");
    const double len = glm::length(*p.obliqueDir);
    if (!(len > 0)) throw Error("camera: the oblique direction is zero");
    dir = *p.obliqueDir / len;
  } else if (p.obliqueAnglesDeg) {
    // Shear angles: AX turns the direction towards +U, AY towards +V:
    // dir = normalize(−W + tan(AX)·U + tan(AY)·V).
    const glm::dvec2 a = *p.obliqueAnglesDeg;  // each in (−89°, 89°): the schema's range
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

namespace {

const ParamSpec kObliqueDir =
    ParamSpec("oblique_dir", ParamKind::Vec3, fieldAccess<&CameraParams::obliqueDir>())
        .withHelp("Common ray direction X,Y,Z (world space, any length)")
        .withDefaultRule("none: give oblique_dir or oblique_angles")
        .withConflicts({"oblique_angles"});
const ParamSpec kObliqueAngles =
    ParamSpec("oblique_angles", ParamKind::Vec2, fieldAccess<&CameraParams::obliqueAnglesDeg>())
        .withUnit("degrees")
        .withHelp("Shear angles AX,AY of the rays towards +U and +V")
        .withDefaultRule("none: give oblique_dir or oblique_angles")
        .withRange(ParamRange::open(-89.0, 89.0))
        .withConflicts({"oblique_dir"});

std::unique_ptr<CameraBase> makeObliqueCamera(const CameraParams& p,
                                              const glm::dvec3& renderOrigin) {
  const CameraFrame frame = frameFromParams(p);
  return std::make_unique<ParallelCamera>(p, renderOrigin, "oblique", obliqueDirection(p, frame));
}

}  // namespace

const CameraModel& obliqueModel() {
  static const CameraModel m{
      "oblique", "parallel rays along a common direction that differs from the view axis",
      makeObliqueCamera,
      joinParamSpecs({commonParamSpecs(), {&viewportParamSpec(), &kObliqueDir, &kObliqueAngles}})};
  return m;
}

}  // namespace aperture
