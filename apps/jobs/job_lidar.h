#pragma once
// A job file's "lidars": LiDAR sensors scanned beside the cameras, through the scene the job
// builds (docs/lidar.md, docs/batch.md). Each entry is an `aperture scan` in JSON.
#include <string>
#include <vector>

#include "apps/jobs/job_json.h"
#include "apps/services/scan.h"

namespace aperture::app {

/// One entry of "lidars", checked (prepareScan) when the job is read.
struct JobLidar {
  ScanRequest request;  ///< paths resolved against the job's directory
  PreparedScan prepared;
};

/// Reads `top`'s "lidars" (absent: none): each entry an object with "lidar" (a spec path or a
/// preset; required), "output" (required; {sweep}), "trajectory", "trajectory_times",
/// "sweeps", "start" (seconds), "frame", "returns", "surfaces", "properties", "label" and
/// "noise" {"sigma", "dropout", "seed"}, as the flags of `aperture scan`. Errors name the
/// file and the key path (lidars[1].frame).
std::vector<JobLidar> readJobLidars(const Object& top, const std::string& baseDir);

}  // namespace aperture::app
