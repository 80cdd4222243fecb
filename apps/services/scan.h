#pragma once
// The LiDAR scan loop (issue 42): a sweep's rays (cameras/lidar/lidar.h) traced through the
// scene, each hit turned into a point with the fields of docs/lidar.md its output needs, and the
// sweeps of a command written as point clouds or range images (core/points/point_writers.h).
// `aperture scan`, job files and Python's Scene.scan share it.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "apps/services/scene_setup.h"
#include "cameras/lidar/lidar.h"
#include "core/points/point_cloud.h"
#include "core/points/point_writers.h"

namespace aperture::app {

/// The frame points are written in: the sensor frame at the time each ray fired (what the
/// sensor reports), world coordinates, or the sensor frame at the sweep's start (deskewed).
enum class ScanFrame { Sensor, World, SweepStart };
ScanFrame parseScanFrame(const std::string& name);  ///< sensor|world|sweep-start, else Error
const char* scanFrameName(ScanFrame frame);

/// Which surfaces along a ray become points: the first, the last or the strongest (highest
/// intensity) of up to ScanOptions::maxSurfaces, or all of them (return_number / returns).
/// First is the closest hit; the others come from the layered hits' search
/// (core/engine/layers.h traceSurfaces: one traversal collecting the nearest surfaces).
enum class ScanReturns { First, Last, Strongest, All };
ScanReturns parseScanReturns(const std::string& name);  ///< first|last|strongest|all, else Error
const char* scanReturnsName(ScanReturns returns);

/// The face property a scan reads as reflectance when the mesh has it: percent (0..100 → 0..1).
inline constexpr const char* kReflectanceProperty = "reflectance";

/// Throws Error "`what` N is outside 1..64" unless 1 <= `surfaces` <= 64, the surfaces a ray
/// looks for (ScanOptions::maxSurfaces); `what` names the argument ("--surfaces").
void checkSurfacesPerRay(int surfaces, const char* what);

/// How one sweep is traced and what its points hold.
struct ScanOptions {
  ScanFrame frame = ScanFrame::Sensor;
  ScanReturns returns = ScanReturns::First;
  /// Surfaces looked for along a ray for last / strongest / all (1..64); first needs 1.
  int maxSurfaces = 4;
  /// Metres past a surface before the next one is looked for (last / strongest / all): a
  /// sensor's two returns are never closer, and the triangles that meet at an edge (or the two
  /// of a quad along its diagonal) are one surface, not two.
  double returnSeparation = 0.01;
  RangeNoise noise;
  /// Face properties carried as uint32 fields of the same name (0xFFFFFFFF where the mesh
  /// lacks them).
  std::vector<std::string> faceProperties;
  /// The fields computed and stored (pointFieldsWrittenAs of the output's format; Python's
  /// fields=): the others are left out of the cloud. A range image adds what it is made from.
  PointFieldSelection fields;
};

/// One traced sweep: its point cloud (hits only, firing order) and its range image (rows ×
/// columns, misses 0), with the tally.
struct ScanSweep {
  PointCloud cloud;
  RangeImage image;
  size_t rays = 0, points = 0;
  double traceSeconds = 0;  ///< tracing and fields, without writing
};

/// The scan loop: traces sweeps of `sensor` through `scene` with `options` on the parallel
/// loop, in two passes over fixed chunks of rays (the same points on any thread count): the
/// trace pass leaves each chunk's hits, compacted, in a buffer the scanner keeps from one
/// sweep to the next; the fields pass writes each chunk's points from the offset the counts
/// of the chunks before it give. The scene, sensor and options must outlive it.
class SweepScanner {
 public:
  /// Error for maxSurfaces outside 1..64.
  SweepScanner(const Scene& scene, const LidarSensor& sensor, const ScanOptions& options);
  ~SweepScanner();
  SweepScanner(const SweepScanner&) = delete;
  SweepScanner& operator=(const SweepScanner&) = delete;

  /// Traces `rays` (one sweep of the sensor). With `rangeImage`, also fills the range image
  /// (Error for ScanReturns::All, which has no image).
  ScanSweep scan(const LidarRays& rays, bool rangeImage = false);
  /// Hands back a sweep this scanner returned, once its points are written: the next scan
  /// fills its point fields in the same memory instead of mapping (and the kernel clearing)
  /// new pages for them.
  void recycle(ScanSweep&& done);

 private:
  struct State;
  const Scene& scene_;
  const LidarSensor& sensor_;
  ScanOptions options_;
  std::unique_ptr<State> state_;
};

/// One sweep through a scanner of its own.
ScanSweep scanSweep(const Scene& scene, const LidarSensor& sensor, const LidarRays& rays,
                    const ScanOptions& options, bool rangeImage = false);

/// Scene options for a scan: withScanNeeds of the scene's.
SceneSpec scanSceneSpec(const SceneOptions& scene, const ScanOptions& options);
/// `spec` with what a scan of `options` needs of the scene: the face properties it carries,
/// "reflectance" when every mesh is a PLY file that has it, and the BVH's context filter for
/// the multi-return search (scanNeedsContextFilter). The one place that derives it (the
/// command, job files and Python's Scene.scan call it).
SceneSpec withScanNeeds(SceneSpec spec, const ScanOptions& options);
/// Whether a scan of `options` is faster on a scene built with BuildOptions::contextFilter:
/// last, strongest and all returns, when the layers' default method is Filter
/// (core/engine/layers.h). A scene without it gives the same points through Retrace (but for
/// surfaces closer than one float ulp, which only a returnSeparation of 0 reports apart).
bool scanNeedsContextFilter(const ScanOptions& options);

/// `pattern` with {sweep} or {sweep:0Nd} (N in 1..20) replaced by `sweep`; Error for any
/// other brace. A pattern without {sweep} is only allowed for one sweep (checked by runScan).
std::string expandSweepPattern(const std::string& pattern, int sweep);

/// `aperture scan`.
/// The start of sweep `sweep` when the first one starts at `firstStartNs` (--start): that plus
/// `sweep` periods; nullopt without it (sweepRays then starts at the trajectory's first time
/// plus `sweep` periods).
inline std::optional<int64_t> sweepStartNs(std::optional<int64_t> firstStartNs, int sweep,
                                           int64_t periodNs) {
  if (!firstStartNs) return std::nullopt;
  return *firstStartNs + int64_t(sweep) * periodNs;
}

struct ScanRequest {
  SceneOptions scene;
  std::string lidar;            ///< spec file or preset name
  std::string trajectory;       ///< TUM or KITTI poses; empty: static at the identity
  std::string trajectoryTimes;  ///< KITTI times file
  int sweeps = 1;
  std::optional<int64_t> startNs;
  ScanOptions options;
  std::string out;         ///< path pattern, format by extension
  std::string labelField;  ///< face property used as LAS classification / SemanticKITTI label
  int columns = 0;         ///< override the sensor's columns per sweep (0: the spec's)
  int threads = 0;         ///< 0: every core
  bool bench = false;      ///< also time bare Embree on the same rays (stderr)
  bool quiet = false;
};

/// What prepareScan checked and read: the sensor, the trajectory and each sweep's path.
struct PreparedScan {
  LidarSensor sensor;
  Trajectory trajectory;
  std::vector<std::string> paths;
  bool image = false;  ///< the format is a range image
};
/// Checks a scan before any scene is loaded: sweeps, output pattern and format, returns,
/// noise, label, the sensor (read), the trajectory (read) and that every sweep lies within it,
/// and that the output directories exist. Errors name the file and the field.
PreparedScan prepareScan(const ScanRequest& request);
/// Traces and writes every sweep of a prepared scan through `scene` (progress on stderr unless
/// request.quiet; with request.bench, the timing against bare Embree on stdout).
void writeScans(const Scene& scene, const ScanRequest& request, const PreparedScan& prepared,
                const std::string& isa, int threads);

/// Checks everything (sensor, trajectory, sweep times, output pattern and format, fields)
/// before loading the scene, then traces and writes each sweep atomically. Errors name the
/// file and the field; nothing is written on bad input.
void runScan(const ScanRequest& request);

}  // namespace aperture::app
