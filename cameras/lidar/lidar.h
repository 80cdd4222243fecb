#pragma once
// LiDAR sensors: a table of beams and a clock instead of a pixel grid (issue 42). A sensor is
// read from aperture's own JSON spec, Ouster's sensor metadata JSON, a Velodyne calibration
// YAML (the ROS velodyne_pointcloud driver's), a Livox-style pattern CSV or a preset name;
// docs/lidar.md gives every format and convention. sweepRays() turns one sweep into world
// rays, each with its firing time and the sensor's pose at that time (trajectory.h).
//
// Frames (issue 42, "Definitions"):
//  - the *lidar frame* is the one the beam angles are measured in: +z the spin axis, azimuth
//    ψ counter-clockwise from +x seen from +z, elevation φ up from the xy plane, a beam
//    direction (cos ψ·cos φ, sin ψ·cos φ, sin φ);
//  - the *sensor frame* is the one points are reported in and whose pose a Trajectory gives:
//    p_sensor = sensorFromLidar · p_lidar (Ouster's lidar_to_sensor_transform; the spec's
//    "mounting" otherwise, identity by default);
//  - units are metres and seconds inside; Ouster's millimetres are converted on reading.
// Time: integer nanoseconds. Sweep k starts at the trajectory's first time plus k sweep
// periods (or at a given start). Spinning: column m (the measurement id, in firing order)
// fires at m·columnTimeNs (default m·periodNs / columns, integer division) after the sweep's
// start, plus its beam's timeOffsetNs. Pattern: the table's rays at their own times, the table
// repeating every patternPeriodNs from the first sweep's start.
#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cameras/lidar/trajectory.h"
#include "core/engine/camera.h"
#include "core/queries/trace.h"

namespace aperture {

/// One beam (laser) of a spinning sensor: a row of its beam table. Row 0 is the table's first
/// entry (Ouster: the highest beam; Velodyne: laser_id 0); `ring` is this index.
struct LidarBeam {
  double elevationDeg = 0;  ///< φ, degrees up from the lidar frame's xy plane
  /// Azimuth offset from the column's encoder angle, degrees, counter-clockwise (Ouster's
  /// beam_azimuth_angles negated; Velodyne's rot_correction in degrees).
  double azimuthDeg = 0;
  int64_t timeOffsetNs = 0;  ///< fires this long after its column (sensors firing in groups)
  /// Beam origin in the lidar frame at encoder angle 0, metres; it turns with the head
  /// (Ouster: beam_to_lidar_transform's translation; Velodyne: from its offset corrections).
  glm::dvec3 origin{0.0};
  /// Metres added to the distance travelled from `origin` to give the reported range
  /// (Ouster: |beam_to_lidar origin| = n of its XYZLut; 0 for the others).
  double rangeOffset = 0;
  /// Velodyne's dist_correction, metres: a correction of the raw count the sensor applies
  /// itself; kept for reference, it does not move any ray.
  double distCorrection = 0;
};

/// One ray of a pattern sensor (Livox): its time within the pattern and direction.
struct PatternRay {
  int64_t timeNs = 0;       ///< from the pattern's start, increasing down the table
  double azimuthDeg = 0;    ///< ψ, counter-clockwise from +x
  double elevationDeg = 0;  ///< φ (Livox's CSV gives the zenith angle, 90° − φ)
};

enum class LidarKind { Spinning, Pattern };

/// Where a spec came from, for messages: "VLP-16 (preset)", "path/to/os1.json".
struct LidarSource {
  std::string path;    ///< the file read, or the preset's name
  std::string format;  ///< "aperture", "ouster", "velodyne", "livox", with " preset" if one
};

/// A LiDAR sensor, checked: every field below is valid once loadLidar returns it.
struct LidarSensor {
  std::string name;  ///< the spec's "name", the preset's, or the file's stem
  LidarSource source;
  LidarKind kind = LidarKind::Spinning;

  // Spinning sensors.
  std::vector<LidarBeam> beams;  ///< the beam table, ring = index
  int columns = 0;               ///< columns (firings of every beam) per sweep
  /// Encoder angle of column 0, degrees, counter-clockwise from +x (Ouster: 0).
  double firstColumnAzimuthDeg = 0;
  /// +1: column angles grow counter-clockwise seen from +z; −1: clockwise (Ouster's encoder
  /// angle 2π − m·2π/w; Velodyne's rotation), the default.
  int spin = -1;
  /// Time between columns, ns; 0 means periodNs() / columns (column m at m·periodNs/columns).
  int64_t columnTimeNs = 0;
  /// Ouster's pixel_shift_by_row (one per beam; empty for others): how the outputs destagger.
  std::vector<int> pixelShiftByRow;
  /// Ouster's column_window, inclusive [first, last] measurement ids with data (first > last
  /// wraps past the last column); rays are emitted only for these. Default: every column.
  std::array<int, 2> columnWindow{0, -1};

  // Pattern sensors.
  std::vector<PatternRay> pattern;  ///< times increasing, all below patternPeriodNs
  int64_t patternPeriodNs = 0;      ///< the table repeats with this period

  // Every sensor.
  double sweepRateHz = 10;  ///< sweeps (turns) per second, > 0
  double minRange = 0;      ///< metres of reported range; closer hits are not returned
  double maxRange = 1e9;    ///< metres of reported range; farther hits are not returned
  /// The lidar frame in the sensor frame: p_sensor = sensorFromLidar · p_lidar (rigid, metres).
  glm::dmat4 sensorFromLidar{1.0};

  /// The sweep period, ns: round(1e9 / sweepRateHz).
  int64_t periodNs() const;
  /// Measurement ids in the column window, in firing order (Spinning).
  std::vector<int> windowColumns() const;
  /// Firing time of column m, ns from the sweep's start (Spinning).
  int64_t columnTime(int m) const;
  /// Encoder angle ψ of column m, degrees: firstColumnAzimuthDeg + spin·m·360/columns.
  double columnAzimuthDeg(int m) const;
  /// Beams per column for a spinning sensor, 1 for a pattern.
  int rows() const { return kind == LidarKind::Spinning ? int(beams.size()) : 1; }
};

/// Names of the built-in presets (VLP-16, HDL-32E, HDL-64E, OS1-64, OS1-128).
std::vector<std::string> lidarPresetNames();
/// The text of a preset's file (cameras/lidar/presets/NAME.json), compiled in; throws Error
/// with "did you mean" for an unknown name.
const std::string& lidarPresetText(const std::string& name);

/// Reads a sensor: a path to a file (the format is told by its content: aperture's JSON spec,
/// Ouster's metadata JSON, legacy or nested, Velodyne's calibration YAML, a Livox CSV), or a
/// preset name. Throws Error naming the file and the field for a malformed or inconsistent
/// spec (a beam table of the wrong length, a missing field, a non-positive rate), and an
/// unknown preset with "did you mean".
LidarSensor loadLidar(const std::string& specOrPreset);
/// The same from text already in memory; `source` names it in messages and picks nothing.
LidarSensor loadLidarText(const std::string& text, const std::string& source);

/// One sweep's rays, flat SoA in firing order (spinning: column by column of the window, each
/// column's beams in table order; pattern: table order). World origins and directions are
/// double; they are anchored to the scene's render origin, as cameras' are, only when rounded
/// to float (fillLidarLanes, lidarTraceRays). A flat batch rather than a Camera: rays carry
/// their own times and poses and come from a table, not a pixel grid, so the frame loop's
/// block walk does not fit; the scan loop packs them into Embree packets (fillLidarLanes), and
/// tests and the bench's bare-Embree baseline take them as TraceRays (lidarTraceRays).
struct LidarRays {
  int sweep = 0;
  int64_t sweepStartNs = 0;  ///< trajectory time of the sweep's start
  int64_t periodNs = 0;
  int rows = 0;     ///< beams per column (1 for a pattern)
  int columns = 0;  ///< columns of the sensor (for a pattern: rays in this sweep)

  std::vector<glm::dvec3> origin;     ///< world, metres: where the ray leaves (beam origin)
  std::vector<glm::dvec3> direction;  ///< world, unit length
  std::vector<int64_t> timeNs;        ///< firing time, ns from sweepStartNs
  std::vector<uint32_t> ring;         ///< beam table index (0 for a pattern)
  std::vector<uint32_t> column;       ///< measurement id (pattern: index in the sweep)
  std::vector<float> azimuthDeg;      ///< ψ of the ray in the lidar frame, [0, 360)
  std::vector<float> elevationDeg;    ///< φ of the ray in the lidar frame
  /// Metres from the ray's origin to the reported range's zero: range = t + rangeOffset.
  std::vector<float> rangeOffset;
  /// Travel distances to trace, [tnear, tfar] along the ray from minRange and maxRange.
  std::vector<float> tnear, tfar;
  std::vector<uint32_t> poseIndex;  ///< per ray, its pose in `poses`
  std::vector<Pose> poses;          ///< worldFromSensor at each distinct firing time
  Pose sweepStartPose;              ///< worldFromSensor at sweepStartNs
  glm::dmat4 sensorFromLidar{1.0};

  size_t size() const { return origin.size(); }
  const Pose& poseOf(size_t i) const { return poses[poseIndex[i]]; }
  /// The world point at distance t along ray i, in the sensor frame at the ray's firing time.
  glm::dvec3 sensorPointAt(size_t i, double t) const;
};

/// Rays of sweep `sweep` (0, 1, ...). The sweep starts at `startNs` if given, else at
/// trajectory.startNs() + sweep·periodNs. Every firing time must lie within the trajectory
/// (a static one holds at every time): Error naming the time and the trajectory otherwise.
LidarRays sweepRays(const LidarSensor& sensor, const Trajectory& trajectory, int sweep,
                    std::optional<int64_t> startNs = std::nullopt);

/// Writes rays [first, first + lanes) of `rays` into packet lanes (render space: origin minus
/// `renderOrigin`, rounded once; unit directions; tnear/tfar from the ray; time 0, mask −1,
/// id = lane), sealed as sealLanes would: valid[k] = −1 for a ray Embree can take
/// (traceableRay), else 0 with the empty segment tnear 1, tfar 0 (lanes past the end too, with
/// finite values). The packet may go to intersect<N> with `activeTraceable`.
void fillLidarLanes(const LidarRays& rays, size_t first, const glm::dvec3& renderOrigin,
                    RayLanes& out, int* valid);

/// The rays as core/queries/trace.h takes them: render space (origin − renderOrigin, rounded
/// once), unit directions, [tnear, tfar] of each ray.
std::vector<TraceRay> lidarTraceRays(const LidarRays& rays, const glm::dvec3& renderOrigin);

/// Range noise and dropout, off by default. Every value is a pure function of (seed, sweep,
/// ray index), so the thread count never changes a cloud.
struct RangeNoise {
  double sigma = 0;    ///< metres, standard deviation of a Gaussian added to the range
  double dropout = 0;  ///< probability in [0, 1) that a return is lost
  uint64_t seed = 0;
  bool enabled() const { return sigma > 0 || dropout > 0; }
};

/// The noisy range of ray `index` of sweep `sweep`: range + σ·N(0,1), or nothing when it
/// drops out. With noise off, `range` itself. Throws Error for σ < 0 or dropout ∉ [0, 1).
std::optional<double> applyRangeNoise(const RangeNoise& noise, double range, int sweep,
                                      uint64_t index);

}  // namespace aperture
