// Thin-lens camera: the perspective camera with a lens disk of radius R on the (U, V) plane
// at e, focused at depth f along −W. The ray code is PerspectiveCamera::rayAt.
#include <cmath>

#include "cameras/models/camera_models.h"
#include "cameras/models/perspective.h"
#include "core/util/error.h"
#include "core/util/vector_kernel.h"

namespace aperture {

namespace {

/// The kernel of generateThinLensCentres for a kBW x kBH block; u and v of the pixel centres
/// come from the camera's tables (no per-ray divide for them).
template <int kBW, int kBH>
void thinLensCentres(const ThinLensCentres& c, int x0, int y0, RayLanes& out, int* valid) {
  constexpr int kLanes = kBW * kBH;
  const double* __restrict us = c.columnU + x0;
  const double* __restrict vs = c.rowV + y0;
  alignas(64) float dx[kLanes], dy[kLanes], dz[kLanes];
  alignas(64) double laneU[kLanes], laneV[kLanes];
  spreadOverLanes<kBW, kBH>(us, vs, laneU, laneV);
  APERTURE_LANE_LOOP
  for (int k = 0; k < kLanes; ++k) {
    const double u = laneU[k], v = laneV[k];
    const double tx = ((u * c.u.x + v * c.v.x) - c.dW.x) * c.focusOverD - c.lens.x;
    const double ty = ((u * c.u.y + v * c.v.y) - c.dW.y) * c.focusOverD - c.lens.y;
    const double tz = ((u * c.u.z + v * c.v.z) - c.dW.z) * c.focusOverD - c.lens.z;
    const double length = std::sqrt((tx * tx + ty * ty) + tz * tz);
    dx[k] = float(tx / length);
    dy[k] = float(ty / length);
    dz[k] = float(tz / length);
  }
  writeBlockLanesFromOrigin<kLanes>(out, c.origin, dx, dy, dz);
  writeBlockInImage<kBW, kBH>(x0, y0, c.width, c.height, valid);
}

const ParamSpec kAperture =
    ParamSpec("aperture", ParamKind::Number, fieldAccess<&CameraParams::apertureRadius>())
        .withUnit("scene units")
        .withHelp("Lens radius (0: pinhole)")
        .withRange(ParamRange::atLeast(0.0));
const ParamSpec kFocus =
    ParamSpec("focus", ParamKind::Number, fieldAccess<&CameraParams::focusDistance>())
        .withUnit("scene units")
        .withHelp("Distance of the in-focus plane along the view axis")
        .withDefault(1.0, "|at - eye| with a look-at point, else {}")
        .withRange(ParamRange::above(0.0));

std::unique_ptr<CameraBase> makeThinLensCamera(const CameraParams& p,
                                               const glm::dvec3& renderOrigin) {
  return std::make_unique<PerspectiveCamera>(p, renderOrigin, "thinlens", p.apertureRadius,
                                             focusDistanceOf(p));
}

}  // namespace

double focusDistanceOf(const CameraParams& p) {
  if (p.focusDistance) return *p.focusDistance;
  return p.at ? glm::length(*p.at - p.eye) : kFocus.defaultAs<double>();
}

bool generateThinLensCentres(const ThinLensCentres& c, const PacketRequest& req, RayLanes& out,
                             int* valid) {
  return withBlockShape(req.blockW, req.blockH, [&](auto bw, auto bh) {
    constexpr int kBW = decltype(bw)::value, kBH = decltype(bh)::value;
    runKernel<&thinLensCentres<kBW, kBH>>(c, req.x0, req.y0, out, valid);
  });
}

const CameraModel& thinLensModel() {
  static const CameraModel m{"thinlens",
                             "perspective with a lens disk: depth of field, focused at `focus`",
                             makeThinLensCamera,
                             joinParamSpecs({commonParamSpecs(),
                                             {&distanceParamSpec(), &viewportParamSpec()},
                                             perspectiveParamSpecs(),
                                             {&kAperture, &kFocus}})};
  return m;
}

}  // namespace aperture
