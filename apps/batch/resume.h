#pragma once
// `aperture batch --resume`: whether an image's existing output can be kept (it must match
// the job, not merely exist). The temporaries that killed processes left behind are found by
// core/io/atomic_file.h (findTemporaries).
#include <string>

#include "apps/jobs/job.h"
#include "core/engine/camera.h"

namespace aperture::app {

/// What --resume found at an image's output.
struct OutputCheck {
  enum class State { Reusable, Missing, Stale };
  State state = State::Missing;
  std::string reason;  ///< for Stale: why, e.g. "size 640x480, job wants 800x600"
};

/// Checks the output of `image`. Reusable only when the EXR is complete (every scanline
/// decodes) and matches the job: the image's size, the channel names writeExr gives the job's
/// AOVs, and the camera attributes (type, eye, U, V, W, d, viewport, spp, extras) that
/// describeWithoutCounts() gives for the image's camera (no direction table is built); with --deep,
/// when the deep file of the layers decodes and has the image's size and the job's layer count;
/// when every dataset file ("outputs") exists (they are written atomically and record no camera, so
/// existing is all that is checked); and, when the job has a preview pattern, when the preview
/// exists, decodes (OpenImageIO) and has the image's size. Missing when there is no EXR (for a job
/// without one: no first dataset file); Stale otherwise, with the first mismatch found.
OutputCheck checkOutput(const Job& job, const JobImage& image);

/// The first difference between the camera recorded in a file and the one the job wants, as
/// "eye (0, 0, 5), job wants (0, 0, 6)"; "" when type, eye, U, V, W, d, viewport, spp, the
/// extras (compared as sorted name/value pairs, the counted ones left out: isCountedExtra) and
/// a calibrated camera's lens (model, parameters, pixel convention) are all equal. Matrices are
/// not compared.
std::string cameraDifference(const CameraDescription& file, const CameraDescription& job);

}  // namespace aperture::app
