// `aperture scan`: LiDAR sweeps of a mesh written as point clouds or range images
// (apps/services/scan.h; docs/lidar.md holds the sensors, frames, fields and formats).
#include <memory>

#include "apps/cli/commands.h"
#include "apps/cli/scene_flags.h"
#include "apps/services/scan.h"
#include "cameras/lidar/trajectory.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

struct ScanArgs {
  ScanRequest request;
  std::string frame = "sensor", returns = "first", start;
  double sigma = 0, dropout = 0;
  uint64_t seed = 0;
};

int runScanCommand(ScanArgs& a) {
  ScanRequest& r = a.request;
  r.options.frame = parseScanFrame(a.frame);
  r.options.returns = parseScanReturns(a.returns);
  if (r.options.returns == ScanReturns::First) r.options.maxSurfaces = 1;
  r.options.noise = {a.sigma, a.dropout, a.seed};
  if (!a.start.empty()) r.startNs = parseTimeNs(a.start, "--start");
  if (r.threads < 0 || r.threads > 4096)
    throw Error(cat("--threads ", r.threads, " must be in [0, 4096]"));
  if (!r.labelField.empty() &&
      std::find(r.options.faceProperties.begin(), r.options.faceProperties.end(), r.labelField) ==
          r.options.faceProperties.end())
    r.options.faceProperties.push_back(r.labelField);
  runScan(r);
  return 0;
}

}  // namespace

Command addScanCommand(CLI::App& app) {
  auto args = std::make_shared<ScanArgs>();
  ScanRequest& r = args->request;
  CLI::App* sub = app.add_subcommand(
      "scan", "LiDAR sweeps of the mesh as point clouds or range images (docs/lidar.md)");
  addSceneOptions(*sub, r.scene);
  sub->add_option("--lidar", r.lidar,
                  "Sensor: aperture's JSON spec, Ouster's metadata JSON, a Velodyne calibration "
                  "YAML, a Livox pattern CSV, or a preset (VLP-16, HDL-32E, HDL-64E, OS1-64, "
                  "OS1-128)")
      ->required()
      ->type_name("SPEC|PRESET");
  sub->add_option("--trajectory", r.trajectory,
                  "Poses of the sensor frame in the world: TUM rows 't tx ty tz qx qy qz qw' or "
                  "KITTI rows with --trajectory-times; none: static at the origin")
      ->type_name("PATH");
  sub->add_option("--trajectory-times", r.trajectoryTimes, "KITTI times file (seconds per row)")
      ->type_name("PATH");
  sub->add_option("--sweeps", r.sweeps, "Sweeps to scan")->capture_default_str();
  sub->add_option("--start", args->start,
                  "Trajectory time of the first sweep's start, seconds (default: the "
                  "trajectory's first time)")
      ->type_name("SECONDS");
  sub->add_option("--frame", args->frame,
                  "Points in the sensor frame at each ray's firing time (sensor), the world "
                  "(world) or the sensor frame at the sweep's start (sweep-start)")
      ->capture_default_str();
  sub->add_option("--returns", args->returns,
                  "Which surfaces along a ray become points: first, last, strongest (of up to "
                  "--surfaces), or all (point clouds only)")
      ->capture_default_str();
  sub->add_option("--surfaces", r.options.maxSurfaces,
                  "Surfaces looked for along a ray for last, strongest and all (1..64)")
      ->capture_default_str();
  sub->add_option("--return-separation", r.options.returnSeparation,
                  "Metres past a surface before the next return is looked for")
      ->capture_default_str()
      ->type_name("M");
  sub->add_option("--property", r.options.faceProperties,
                  "Face property of the mesh carried as a uint32 field (repeatable)")
      ->type_name("NAME");
  sub->add_option("--label", r.labelField,
                  "Face property written as LAS classification and SemanticKITTI label")
      ->type_name("NAME");
  sub->add_option("--noise-sigma", args->sigma, "Gaussian range noise, metres (0: off)")
      ->type_name("S");
  sub->add_option("--dropout", args->dropout, "Probability in [0, 1) that a return is lost")
      ->type_name("P");
  sub->add_option("--seed", args->seed, "Seed of the noise (same seed, same cloud)")
      ->type_name("N");
  sub->add_option("--columns", r.columns,
                  "Columns per sweep instead of the sensor's (spinning sensors)")
      ->type_name("N");
  sub->add_option("--out", r.out,
                  "Output path, format by extension: .ply .pcd .las .bin (+ .label) point "
                  "clouds, .npz .exr range images; {sweep} or {sweep:06d} numbers the sweeps")
      ->required()
      ->type_name("PATH");
  sub->add_option("--threads", r.threads, "Worker threads in [0, 4096] (0 = all cores)");
  sub->add_flag("--bench", r.bench,
                "Also time the scan loop and bare Embree on the same rays (best of 15, stdout)");
  sub->add_flag("--quiet", r.quiet, "No progress or log lines");
  return [args] { return runScanCommand(*args); };
}

}  // namespace aperture::app
