#include "cameras/parallel_projection.h"

#include <cmath>

#include "core/error.h"

namespace aperture {

ParallelCamera::ParallelCamera(const CameraParams& p, const glm::dvec3& renderOrigin,
                               const char* typeName, const glm::dvec3& worldDir)
    : PacketCamera(p, renderOrigin, typeName), dir_(worldDir) {
  rejectShift();
  if (!p.viewport)
    throw Error(cat("camera: '", type_,
                    "' needs --viewport VW,VH in world units (a field of view does not define "
                    "a parallel projection)"));
  const double forward = -glm::dot(dir_, frame_.w);
  shearU_ = glm::dot(dir_, frame_.u) / forward;
  shearV_ = glm::dot(dir_, frame_.v) / forward;
}

std::optional<glm::dvec2> ParallelCamera::project(const glm::dvec3& worldPoint) const {
  const glm::dvec3 p = worldPoint - frame_.e;
  const double depth = -glm::dot(p, frame_.w);
  if (depth < 0) return std::nullopt;
  return planeToRaster(glm::dot(p, frame_.u) - shearU_ * depth,
                       glm::dot(p, frame_.v) - shearV_ * depth);
}

ViewVolume ParallelCamera::viewVolume(double nearDist, double farDist) const {
  const bool ortho = shearU_ == 0 && shearV_ == 0;
  return ViewVolume::planar(ortho ? ViewVolume::Kind::Box : ViewVolume::Kind::Parallelepiped,
                            frame_.e, frame_.u, frame_.v, frame_.w, nearDist, farDist,
                            {uLo(), shearU_}, {uHi(), shearU_}, {vLo(), shearV_}, {vHi(), shearV_});
}

std::optional<glm::dmat4> ParallelCamera::planeFromCamera() const {
  // Camera space (x, y, z), z the depth: the ray through (u, v) reaches depth z at
  // x = u + su·z, y = v + sv·z, so u = x − su·z, v = y − sv·z; z' = z (NDC z is Z), w = 1.
  // GLM: m[column][row].
  glm::dmat4 m(1.0);
  m[2][0] = -shearU_;
  m[2][1] = -shearV_;
  return m;
}

void ParallelCamera::describeExtra(CameraDescription& c) const {
  c.extra.emplace_back("direction", cat(dir_.x, ",", dir_.y, ",", dir_.z));
  c.extra.emplace_back("shear", cat(shearU_, ",", shearV_));
}

}  // namespace aperture
