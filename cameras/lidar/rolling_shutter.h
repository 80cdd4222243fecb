#pragma once
// Rolling-shutter cameras: the same per-ray time as a LiDAR's, one time per image row. Any
// Camera is wrapped; row i is read out at frameStartNs + i·rowReadout and its rays move with
// the trajectory between frameStartNs and that time:
//   worldFromCamera(row i) = T(t_i) · T(t_0)⁻¹ · worldFromCamera(as the camera was built),
// T the trajectory's worldFromSensor. A row whose time is the frame's start (every row at
// zero readout) is the wrapped camera's rays bit for bit.
#include <cstdint>
#include <memory>

#include "cameras/lidar/trajectory.h"
#include "core/engine/camera.h"

namespace aperture {

/// Throws Error for a negative or non-finite readout, a non-positive height, or a row time
/// (frameStartNs + i·rowReadout, i < height) outside `trajectory`, naming the time.
void checkRollingShutter(const Trajectory& trajectory, int64_t frameStartNs,
                         double rowReadoutSeconds, int height);

/// `base` read out row by row, `rowReadoutSeconds` (≥ 0) apart, starting at `frameStartNs`
/// of `trajectory` (whose every row time must lie within it: Error naming the time
/// otherwise, before any ray). `height` is the image's row count; `renderOrigin` the scene's
/// (the camera's rays are in render space). With readout 0 the result generates exactly the
/// rays of `base`. project() uses the frame start's pose.
std::shared_ptr<const Camera> rollingShutterCamera(std::shared_ptr<const Camera> base,
                                                   const Trajectory& trajectory,
                                                   int64_t frameStartNs, double rowReadoutSeconds,
                                                   int height, const glm::dvec3& renderOrigin);

}  // namespace aperture
