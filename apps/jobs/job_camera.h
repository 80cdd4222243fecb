#pragma once
// One camera entry of a job file, read through the camera parameter schema: its keys are
// the schema's parameter names (plus name, orbit, keyframes, frames), so the job file, the
// command line and Python accept the same parameters with the same checks.
#include <string>
#include <utility>
#include <vector>

#include "apps/jobs/job_json.h"
#include "cameras/schema/param_schema.h"

namespace aperture::app {

/// Most images one job may hold (so a malformed file cannot exhaust memory).
inline constexpr size_t kMaxJobImages = 100000;

/// A camera entry expanded into its path frames: (frame number, complete parameters).
struct JobCamera {
  std::string name;
  std::vector<std::pair<int, CameraParams>> frames;
};

/// Keys a camera entry accepts: name, orbit, keyframes, frames, every camera parameter and
/// "blender" (a camera in Blender's property names; see docs/cameras.md).
std::vector<std::string> jobCameraKeys();

/// A JSON value as a value of `spec`'s kind (numbers, [x, y(, z)], [w, h], true/false, a
/// word); errors name the JSON path.
ParamValue paramFromJson(const Object& entry, const ParamSpec& spec, const json& v);

/// Reads camera entry `c` over `defaults` (the job's size and spp) and expands it: a fixed
/// camera (eye and exactly one of at, dir) or a path (orbit or keyframes, which set eye and
/// at). `framesLeft` bounds the frames the entry may add. Every frame's camera is built once
/// to check it. Errors name the file, the JSON path and the camera.
JobCamera parseJobCamera(const Object& c, const CameraParams& defaults, size_t framesLeft);

}  // namespace aperture::app
