#pragma once
// Timestamped poses of a sensor frame in the world, interpolated per ray (linear position,
// slerp rotation): LiDAR sweeps and rolling-shutter cameras take each ray's pose at its own
// time. Times are integer nanoseconds, parsed from the files' decimal text without rounding
// through a double, so a Unix time in seconds keeps every nanosecond.
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <vector>

namespace aperture {

/// A rigid pose aFromB: p_a = rotation · p_b + translation (metres). For a trajectory,
/// worldFromSensor.
struct Pose {
  glm::dvec3 translation{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};  ///< unit quaternion (w, x, y, z)

  glm::dvec3 apply(const glm::dvec3& p) const { return rotation * p + translation; }
  glm::dvec3 applyDirection(const glm::dvec3& d) const { return rotation * d; }
  Pose inverse() const;
  glm::dmat4 matrix() const;  ///< the 4x4 column-vector matrix
  /// The pose of a rigid 4x4 matrix (its rotation block orthonormalised to a quaternion).
  static Pose fromMatrix(const glm::dmat4& m);
};
/// A pose as a rotation matrix and a translation, for applying it to many points: 9 products a
/// point, half what the quaternion takes (the two agree to rounding, not bit for bit).
struct PoseMatrix {
  glm::dmat3 rotation{1.0};
  glm::dvec3 translation{0.0};

  PoseMatrix() = default;
  explicit PoseMatrix(const Pose& pose)
      : rotation(glm::mat3_cast(pose.rotation)), translation(pose.translation) {}
  glm::dvec3 apply(const glm::dvec3& p) const { return rotation * p + translation; }
};

/// a · b: first b, then a (aFromC = aFromB · bFromC).
Pose operator*(const Pose& a, const Pose& b);

/// One row of a trajectory.
struct TimedPose {
  int64_t timeNs = 0;
  Pose pose;  ///< worldFromSensor
};

class Trajectory {
 public:
  /// A static sensor at `pose` (the identity by default): valid at every time, startNs() 0.
  Trajectory() : Trajectory(Pose{}) {}
  explicit Trajectory(const Pose& pose);
  /// Rows with strictly increasing times; one row is a static sensor at that pose (valid at
  /// every time, startNs() its time). `source` names the rows in messages ("poses.txt").
  /// Throws Error for no rows, or a time not after the one before ("SOURCE line N").
  Trajectory(std::vector<TimedPose> rows, std::string source, std::vector<int> lines = {});

  int64_t startNs() const { return rows_.front().timeNs; }
  int64_t endNs() const { return rows_.back().timeNs; }
  bool isStatic() const { return rows_.size() == 1; }
  const std::vector<TimedPose>& rows() const { return rows_; }
  const std::string& source() const { return source_; }

  /// The pose at `timeNs`: linear in position and slerp in rotation between the rows around
  /// it (exactly a row's pose at its time). Throws Error naming the time (in seconds, exact)
  /// and the trajectory when the time lies outside [startNs, endNs] of a moving trajectory.
  Pose at(int64_t timeNs) const;
  /// Whether at(timeNs) is defined.
  bool covers(int64_t timeNs) const;

 private:
  std::vector<TimedPose> rows_;
  std::string source_;
};

/// TUM RGB-D format: one row `t tx ty tz qx qy qz qw` per line (t seconds, the quaternion
/// that turns the sensor frame into the world), '#' comments and blank lines skipped.
Trajectory loadTumTrajectory(const std::string& path);
/// KITTI odometry poses: 12 numbers per line, the 3x4 matrix [R | t] of worldFromSensor row
/// by row, with times (seconds, one per line) from `timesPath`. Errors name the file and line.
Trajectory loadKittiTrajectory(const std::string& posesPath, const std::string& timesPath);
/// TUM when the first row holds 8 numbers, KITTI (with `timesPath`, required) when 12.
Trajectory loadTrajectory(const std::string& path, const std::string& timesPath = "");

/// Decimal seconds ("1305031102.175304", "-2", "1e-3") to integer nanoseconds, exactly for
/// plain decimals (rounded to the nearest ns past nine decimals); throws Error naming `what`.
int64_t parseTimeNs(const std::string& text, const std::string& what);
/// Nanoseconds as decimal seconds, exactly ("1305031102.175304000").
std::string formatTimeNs(int64_t ns);

}  // namespace aperture
