#include "cameras/models/parallel_projection.h"

#include <cmath>

#include "core/util/error.h"
#include "core/util/vector_kernel.h"

namespace aperture {

namespace {

/// What the parallel projections' pixel-centre kernel needs of the camera.
struct ParallelCentres {
  const PixelCentreTable& centres;  ///< u, v of the pixel centres
  int width, height;
  glm::dvec3 eye, u, v;  ///< render-space eye, the frame's U and V
  glm::vec3 dir;         ///< the common direction, rounded once
};

/// A kBW x kBH block of rays through pixel centres, rayAt() term by term: origin
/// (e + u·U) + v·V, u and v from the camera's pixel-centre table.
template <int kBW, int kBH>
void parallelCentres(const ParallelCentres& c, int x0, int y0, RayLanes& out, int* valid) {
  constexpr int kLanes = kBW * kBH;
  const double* __restrict us = c.centres.u.data() + x0;
  const double* __restrict vs = c.centres.v.data() + y0;
  alignas(64) float ox[kLanes], oy[kLanes], oz[kLanes], dx[kLanes], dy[kLanes], dz[kLanes];
  alignas(64) double laneU[kLanes], laneV[kLanes];
  spreadOverLanes<kBW, kBH>(us, vs, laneU, laneV);
  APERTURE_LANE_LOOP
  for (int k = 0; k < kLanes; ++k) {
    const double u = laneU[k], v = laneV[k];
    ox[k] = float((c.eye.x + u * c.u.x) + v * c.v.x);
    oy[k] = float((c.eye.y + u * c.u.y) + v * c.v.y);
    oz[k] = float((c.eye.z + u * c.u.z) + v * c.v.z);
    dx[k] = c.dir.x;
    dy[k] = c.dir.y;
    dz[k] = c.dir.z;
  }
  writeBlockLanesWithOrigins<kLanes>(out, ox, oy, oz, dx, dy, dz);
  writeBlockInImage<kBW, kBH>(x0, y0, c.width, c.height, valid);
}

}  // namespace

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
  centres_ = PixelCentreTable(window());
}

void ParallelCamera::generate(const PacketRequest& req, RayLanes& out, int* valid) const {
  if (spp_ == 1 || req.centreRay()) {
    const ParallelCentres c{centres_, width_,   height_,        renderEyeD_,
                            frame_.u, frame_.v, glm::vec3(dir_)};
    const bool done = withBlockShape(req.blockW, req.blockH, [&](auto bw, auto bh) {
      constexpr int kBW = decltype(bw)::value, kBH = decltype(bh)::value;
      runKernel<&parallelCentres<kBW, kBH>>(c, req.x0, req.y0, out, valid);
    });
    if (done) return;
  }
  PacketCamera::generate(req, out, valid);
}

std::optional<glm::dvec2> ParallelCamera::project(const glm::dvec3& worldPoint) const {
  const glm::dvec3 p = worldPoint - frame_.e;
  const double depth = -glm::dot(p, frame_.w);
  if (depth < 0) return std::nullopt;
  return rasterFromPlane(glm::dot(p, frame_.u) - shearU_ * depth,
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
