#pragma once
// Camera paths of job files: turntable orbits and keyframes, expanded into path frames.
#include <glm/glm.hpp>
#include <optional>
#include <vector>

#include "apps/jobs/job_json.h"
#include "cameras/schema/params.h"

namespace aperture::app {

/// A turntable path: see docs/batch.md for the formula.
struct OrbitPath {
  glm::dvec3 centre{0.0};
  double radius = 1;                   ///< scene units (> 0)
  std::optional<double> height;        ///< offset along up, scene units
  std::optional<double> elevationDeg;  ///< angle above the orbit plane, degrees
  double startDeg = 0;                 ///< azimuth of frame 0, degrees
  double sweepDeg = 360;               ///< azimuth covered by `frames` frames, degrees
  int frames = 1;
  glm::dvec3 up{0.0, 1.0, 0.0};
};

/// Eye position of frame k of an orbit.
glm::dvec3 orbitEye(const OrbitPath& orbit, int k);

/// One keyframe of a keyframed path.
struct Keyframe {
  int frame = 0;
  glm::dvec3 eye{0.0}, at{0.0}, up{0.0, 1.0, 0.0};
  std::optional<double> fovDeg;
};

/// The keyframe values at frame f: linear interpolation between the keyframes around f,
/// held constant before the first and after the last. Keyframes ascend strictly by frame.
Keyframe interpolateKeyframes(const std::vector<Keyframe>& keys, int f);

/// The "orbit" object of camera entry `c` (`base` gives up). Errors name the JSON path.
OrbitPath parseOrbit(const Object& c, const CameraParams& base);
/// The "keyframes" array of camera entry `c` (`base` gives up and fov defaults).
std::vector<Keyframe> parseKeyframes(const Object& c, const CameraParams& base);

}  // namespace aperture::app
