#pragma once
// The union of cameras' view volumes as a world-box test for core/engine/cull.h.
#include <vector>

#include "cameras/geometry/view_volume.h"
#include "cameras/schema/params.h"
#include "core/engine/cull.h"

namespace aperture {

/// Everything the cameras' rays can reach: each camera's view volume with near = 0 and
/// far = +inf (rays start at depth 0 and are unbounded), tested with the volume's relative
/// slack, and each box first grown by the rounding of the cameras' ray origins to float in
/// render space (|origin| · 2^-22, so far-from-anchor eyes in world-space mode stay exact).
struct CameraCuller {
  std::vector<ViewVolume> volumes;
  double pad = 0;               ///< world units added to every side of a tested box
  bool seesEverything = false;  ///< a panorama among the cameras: culling keeps all
  bool mayIntersectBox(const glm::dvec3& lo, const glm::dvec3& hi) const;
  WorldBoxTest test() const;
};

/// The culler for these cameras in a scene whose render origin is `renderOrigin`. Throws
/// Error for a bad camera (as makeCamera) or an empty list.
CameraCuller cullerFor(const std::vector<CameraParams>& cameras, const glm::dvec3& renderOrigin);

}  // namespace aperture
