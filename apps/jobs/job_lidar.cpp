#include "apps/jobs/job_lidar.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "cameras/lidar/trajectory.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

/// `p` against the job's directory unless absolute.
std::string resolvedAgainst(const std::string& baseDir, const std::string& p) {
  const std::filesystem::path path(p);
  return path.is_absolute() || baseDir.empty() ? p
                                               : (std::filesystem::path(baseDir) / path).string();
}

/// A spec path if the file exists beside the job, else the text as a preset name.
std::string lidarSpecOf(const std::string& baseDir, const std::string& given) {
  const std::string resolved = resolvedAgainst(baseDir, given);
  return std::filesystem::exists(resolved) ? resolved : given;
}

JobLidar readLidar(const Object& e, const std::string& baseDir) {
  JobLidar l;
  ScanRequest& r = l.request;
  r.quiet = true;
  if (!e.has("lidar")) e.fail(e.keyPath("lidar"), "required key is missing");
  if (!e.has("output")) e.fail(e.keyPath("output"), "required key is missing");
  r.lidar = lidarSpecOf(baseDir, e.string("lidar").value_or(""));
  r.out = resolvedAgainst(baseDir, e.string("output").value_or(""));
  if (const auto t = e.string("trajectory")) r.trajectory = resolvedAgainst(baseDir, *t);
  if (const auto t = e.string("trajectory_times")) r.trajectoryTimes = resolvedAgainst(baseDir, *t);
  r.sweeps = e.integer("sweeps", 1);
  if (const auto s = e.number("start")) r.startNs = int64_t(std::llround(*s * 1e9));
  try {
    r.options.frame = parseScanFrame(e.string("frame").value_or("sensor"));
  } catch (const Error& err) {
    e.fail(e.keyPath("frame"), err.what());
  }
  try {
    r.options.returns = parseScanReturns(e.string("returns").value_or("first"));
  } catch (const Error& err) {
    e.fail(e.keyPath("returns"), err.what());
  }
  r.options.maxSurfaces = r.options.returns == ScanReturns::First ? 1 : e.integer("surfaces", 4);
  if (e.has("properties")) {
    const json& names = e.array("properties");
    for (size_t k = 0; k < names.size(); ++k) {
      if (!names[k].is_string())
        e.fail(indexPath(e.keyPath("properties"), k), "expected a face property name (a string)");
      r.options.faceProperties.push_back(names[k].get<std::string>());
    }
  }
  if (const auto label = e.string("label")) {
    r.labelField = *label;
    if (std::find(r.options.faceProperties.begin(), r.options.faceProperties.end(), *label) ==
        r.options.faceProperties.end())
      r.options.faceProperties.push_back(*label);
  }
  if (e.has("noise")) {
    const Object n(e.file(), e.keyPath("noise"), e.required("noise"), {"sigma", "dropout", "seed"});
    r.options.noise.sigma = n.number("sigma", 0.0);
    r.options.noise.dropout = n.number("dropout", 0.0);
    r.options.noise.seed = uint64_t(n.integer("seed", 0));
  }
  try {
    l.prepared = prepareScan(r);
  } catch (const Error& err) {
    e.fail(e.path(), err.what());
  }
  return l;
}

}  // namespace

std::vector<JobLidar> readJobLidars(const Object& top, const std::string& baseDir) {
  std::vector<JobLidar> out;
  if (!top.has("lidars")) return out;
  const json& entries = top.array("lidars");
  for (size_t k = 0; k < entries.size(); ++k) {
    const Object e(top.file(), indexPath(top.keyPath("lidars"), k), entries[k],
                   {"lidar", "output", "trajectory", "trajectory_times", "sweeps", "start", "frame",
                    "returns", "surfaces", "properties", "label", "noise"});
    out.push_back(readLidar(e, baseDir));
  }
  return out;
}

}  // namespace aperture::app
