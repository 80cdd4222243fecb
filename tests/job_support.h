#pragma once
// Job files for the tests of jobs and batches (tests/apps/jobs, tests/apps/batch,
// tests/apps/cli): jobs to start from, parsing one and the message it throws, writing one and
// running `aperture batch` on it, the statuses of a summary's images and a job run in shards.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <glm/glm.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "apps/jobs/job.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture::test {

/// `v` as the value of a vector flag (--eye X,Y,Z), every digit of each component.
inline std::string flagValue(const glm::dvec3& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g", v.x, v.y, v.z);
  return buf;
}

/// A valid job to start from: one fixed camera on a procedural sphere.
inline nlohmann::json baseJob() {
  return nlohmann::json::parse(R"({
    "scene": {"meshes": [{"path": "procedural:sphere"}]},
    "cameras": [{"name": "cam", "eye": [0, 0, 5], "at": [0, 0, 0], "fov": 40}],
    "size": [32, 24],
    "output": "out/{camera}_{frame:04d}.exr"
  })");
}

/// Three orbit cameras with four frames each (different radius, elevation/height, up, fov).
inline nlohmann::json orbitJob() {
  return nlohmann::json::parse(R"({
    "scene": {"meshes": [{"path": "procedural:default?tris=20000"}]},
    "cameras": [
      {"name": "low", "orbit": {"centre": [0, 0, 0], "radius": 9, "height": 1.5}, "frames": 4,
       "fov": 45},
      {"name": "high", "orbit": {"centre": [0.5, 0, -0.5], "radius": 11, "elevation": 35,
       "start": 20}, "frames": 4, "fov": 35},
      {"name": "side", "orbit": {"centre": [0, 1, 0], "radius": 8, "height": 0.5, "sweep": 90},
       "frames": 4, "up": [0, 1, 0.1], "fov": 50}
    ],
    "aovs": "all",
    "size": [64, 48],
    "output": "out/{camera}_{frame:04d}.exr",
    "performance": {"threads": 2}
  })");
}

/// Three scenes of different procedural meshes: the first two use the shared cameras, the
/// third its own cameras and its own size (an entry's keys win over the shared ones).
inline nlohmann::json scenesJob() {
  return nlohmann::json::parse(R"({
    "scenes": [
      {"name": "small", "scene": {"meshes": [{"path": "procedural:spheres?tris=3000"}]}},
      {"name": "large", "scene": {"meshes": [{"path": "procedural:spheres?tris=20000"}]}},
      {"name": "ball", "scene": {"meshes": [{"path": "procedural:sphere?radius=2&cx=0.5"}]},
       "cameras": [{"name": "near", "eye": [0, 1, 6], "at": [0, 0, 0], "fov": 50}],
       "size": [40, 30]}
    ],
    "cameras": [
      {"name": "front", "eye": [0, 2, 12], "at": [0, 0, 0], "fov": 45},
      {"name": "orbit", "orbit": {"centre": [0, 0, 0], "radius": 11, "height": 3}, "frames": 2,
       "fov": 40}
    ],
    "aovs": "all",
    "size": [48, 32],
    "output": "out/{scene}/{camera}_{frame}.exr",
    "performance": {"threads": 2}
  })");
}

/// `j` parsed as the job file "job.json" of the folder `baseDir`.
inline app::Job parseJobJson(const nlohmann::json& j, const std::string& baseDir = "") {
  return app::parseJobText(j.dump(), "job.json", baseDir);
}

/// The message parseJobJson throws for `j` ("" if it does not throw).
inline std::string jobParseError(const nlohmann::json& j, const std::string& baseDir = "") {
  try {
    parseJobJson(j, baseDir);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// Writes `j` as DIR/NAME; returns the path.
inline std::string writeJob(const std::string& dir, const nlohmann::json& j,
                            const std::string& name = "job.json") {
  const std::string path = dir + "/" + name;
  writeFile(path, j.dump(2));
  return path;
}

/// Runs `aperture batch ARGS JOB`; returns the exit code, output in *out.
inline int runBatch(const std::string& args, const std::string& jobPath, std::string* out) {
  return runCommand(apertureBinary() + " batch " + args + " " + quote(jobPath), out);
}

/// The status of each image in a summary, by index.
inline std::map<size_t, std::string> imageStatuses(const nlohmann::json& summary) {
  std::map<size_t, std::string> s;
  for (const nlohmann::json& e : summary["images"]) s[e["index"].get<size_t>()] = e["status"];
  return s;
}

/// The indices of a summary's images whose status is `status`.
inline std::set<size_t> imagesWithStatus(const nlohmann::json& summary, const std::string& status) {
  std::set<size_t> s;
  for (const auto& [index, st] : imageStatuses(summary))
    if (st == status) s.insert(index);
  return s;
}

/// Runs every shard of `j` in `dir` with `envFor(k)` before the command and `--shard spec`;
/// returns how often each image index was rendered ok, and checks each shard's summary name.
inline std::map<size_t, int> runShards(const std::string& dir, const nlohmann::json& j,
                                       const std::string& spec, size_t n,
                                       const std::function<std::string(size_t)>& envFor) {
  std::filesystem::create_directories(dir);
  const std::string jobPath = writeJob(dir, j);
  std::map<size_t, int> rendered;
  for (size_t k = 0; k < n; ++k) {
    std::string out;
    const std::string cmd = "env " + envFor(k) + " " + apertureBinary() +
                            " batch --quiet --shard " + spec + " " + quote(jobPath);
    EXPECT_EQ(runCommand(cmd, &out), 0) << cmd << "\n" << out;
    const std::string summaryPath =
        dir + "/out/summary.shard-" + std::to_string(k) + "-of-" + std::to_string(n) + ".json";
    if (!std::filesystem::exists(summaryPath)) {
      ADD_FAILURE() << "no " << summaryPath << " after " << cmd << "\n" << out;
      continue;
    }
    for (size_t index : imagesWithStatus(readJson(summaryPath), "ok")) ++rendered[index];
  }
  return rendered;
}

}  // namespace aperture::test
