#include "cameras/lidar/lidar.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace aperture {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

float wrapDegrees(double deg) {
  double a = std::fmod(deg, 360.0);
  if (a < 0) a += 360.0;
  const float f = float(a);
  return f >= 360.0f ? 0.0f : f;
}

// SplitMix64's finaliser: a full-avalanche 64-bit mix.
uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Uniform in [0, 1) from (seed, sweep, ray index, dimension): a counter-based hash, so the
// value of a ray never depends on which thread draws it or in which order.
double noiseUniform(uint64_t seed, int sweep, uint64_t index, uint64_t dim) {
  uint64_t h = mix64(seed);
  h = mix64(h ^ uint64_t(uint32_t(sweep)));
  h = mix64(h ^ index);
  h = mix64(h ^ (dim * 0xd1b54a32d192ed03ULL));
  return double(h >> 11) * (1.0 / 9007199254740992.0);
}

// One ray's geometry in the lidar frame at its column's encoder angle.
struct LidarRay {
  glm::dvec3 origin, direction;
  double azimuthDeg, elevationDeg;
};

LidarRay beamRay(const LidarBeam& b, double columnDeg) {
  const double psi = (columnDeg + b.azimuthDeg) * kDeg, phi = b.elevationDeg * kDeg;
  const double c = std::cos(columnDeg * kDeg), s = std::sin(columnDeg * kDeg);
  LidarRay r;
  r.direction = {std::cos(psi) * std::cos(phi), std::sin(psi) * std::cos(phi), std::sin(phi)};
  r.origin = {c * b.origin.x - s * b.origin.y, s * b.origin.x + c * b.origin.y, b.origin.z};
  r.azimuthDeg = columnDeg + b.azimuthDeg;
  r.elevationDeg = b.elevationDeg;
  return r;
}

LidarRay patternRay(const PatternRay& p) {
  const double psi = p.azimuthDeg * kDeg, phi = p.elevationDeg * kDeg;
  return {glm::dvec3(0.0),
          {std::cos(psi) * std::cos(phi), std::sin(psi) * std::cos(phi), std::sin(phi)},
          p.azimuthDeg,
          p.elevationDeg};
}

}  // namespace

int64_t LidarSensor::periodNs() const { return std::llround(1e9 / sweepRateHz); }

std::vector<int> LidarSensor::windowColumns() const {
  std::vector<int> ids;
  const int first = columnWindow[0], last = columnWindow[1] < 0 ? columns - 1 : columnWindow[1];
  for (int m = 0; m < columns; ++m) {
    const bool in = first <= last ? (m >= first && m <= last) : (m >= first || m <= last);
    if (in) ids.push_back(m);
  }
  return ids;
}

int64_t LidarSensor::columnTime(int m) const {
  return columnTimeNs > 0 ? int64_t(m) * columnTimeNs : int64_t(m) * periodNs() / columns;
}

double LidarSensor::columnAzimuthDeg(int m) const {
  return firstColumnAzimuthDeg + double(spin) * double(m) * 360.0 / double(columns);
}

glm::dvec3 LidarRays::sensorPointAt(size_t i, double t) const {
  return poseOf(i).inverse().apply(origin[i] + direction[i] * t);
}

LidarRays sweepRays(const LidarSensor& sensor, const Trajectory& trajectory, int sweep,
                    std::optional<int64_t> startNs) {
  if (sweep < 0) throw Error(cat(sensor.name, ": sweep ", sweep, " is negative"));
  LidarRays out;
  out.sweep = sweep;
  out.periodNs = sensor.periodNs();
  out.sweepStartNs = startNs ? *startNs : trajectory.startNs() + int64_t(sweep) * out.periodNs;
  out.sensorFromLidar = sensor.sensorFromLidar;
  const Pose sensorFromLidar = Pose::fromMatrix(sensor.sensorFromLidar);

  // Each ray's lidar-frame geometry and time, in firing order; then the poses.
  std::vector<LidarRay> rays;
  std::vector<int64_t> times;
  std::vector<uint32_t> rings, columns;
  std::vector<double> rangeOffsets;
  if (sensor.kind == LidarKind::Spinning) {
    out.rows = int(sensor.beams.size());
    out.columns = sensor.columns;
    const std::vector<int> ids = sensor.windowColumns();
    rays.reserve(ids.size() * sensor.beams.size());
    for (int m : ids) {
      const double columnDeg = sensor.columnAzimuthDeg(m);
      const int64_t columnTime = sensor.columnTime(m);
      for (size_t b = 0; b < sensor.beams.size(); ++b) {
        rays.push_back(beamRay(sensor.beams[b], columnDeg));
        times.push_back(columnTime + sensor.beams[b].timeOffsetNs);
        rings.push_back(uint32_t(b));
        columns.push_back(uint32_t(m));
        rangeOffsets.push_back(sensor.beams[b].rangeOffset);
      }
    }
  } else {
    // Sweep k covers [k·P, (k+1)·P) of the pattern's own clock, which repeats every Q.
    out.rows = 1;
    const int64_t P = out.periodNs, Q = sensor.patternPeriodNs;
    const int64_t from = int64_t(sweep) * P, to = from + P;
    for (int64_t cycle = from / Q; cycle * Q < to; ++cycle)
      for (const PatternRay& p : sensor.pattern) {
        const int64_t g = cycle * Q + p.timeNs;
        if (g < from || g >= to) continue;
        rays.push_back(patternRay(p));
        times.push_back(g - from);
        rings.push_back(0);
        columns.push_back(uint32_t(rays.size() - 1));
        rangeOffsets.push_back(0);
      }
    out.columns = int(rays.size());
  }

  // Every firing time inside the trajectory, before any pose is taken.
  if (!rays.empty()) {
    const auto [lo, hi] = std::minmax_element(times.begin(), times.end());
    for (int64_t t : {*lo, *hi})
      if (!trajectory.covers(out.sweepStartNs + t))
        throw Error(cat(sensor.name, " sweep ", sweep, ": firing time ",
                        formatTimeNs(out.sweepStartNs + t), " s lies outside the trajectory ",
                        trajectory.source(), " (", formatTimeNs(trajectory.startNs()), " to ",
                        formatTimeNs(trajectory.endNs()), " s)"));
  }
  if (trajectory.covers(out.sweepStartNs))
    out.sweepStartPose = trajectory.at(out.sweepStartNs);
  else if (!times.empty())
    out.sweepStartPose = trajectory.at(out.sweepStartNs + times.front());

  const size_t n = rays.size();
  out.origin.resize(n);
  out.direction.resize(n);
  out.azimuthDeg.resize(n);
  out.elevationDeg.resize(n);
  out.rangeOffset.resize(n);
  out.tnear.resize(n);
  out.tfar.resize(n);
  out.poseIndex.resize(n);
  out.timeNs = std::move(times);
  out.ring = std::move(rings);
  out.column = std::move(columns);
  int64_t lastTime = 0;
  Pose worldFromLidar;
  for (size_t i = 0; i < n; ++i) {
    if (i == 0 || out.timeNs[i] != lastTime) {
      lastTime = out.timeNs[i];
      out.poses.push_back(trajectory.at(out.sweepStartNs + lastTime));
      worldFromLidar = out.poses.back() * sensorFromLidar;
    }
    out.poseIndex[i] = uint32_t(out.poses.size() - 1);
    out.origin[i] = worldFromLidar.apply(rays[i].origin);
    out.direction[i] = glm::normalize(worldFromLidar.applyDirection(rays[i].direction));
    out.azimuthDeg[i] = wrapDegrees(rays[i].azimuthDeg);
    out.elevationDeg[i] = float(rays[i].elevationDeg);
    out.rangeOffset[i] = float(rangeOffsets[i]);
    out.tnear[i] = float(std::max(0.0, sensor.minRange - rangeOffsets[i]));
    out.tfar[i] = float(std::max(0.0, sensor.maxRange - rangeOffsets[i]));
  }
  return out;
}

void fillLidarLanes(const LidarRays& rays, size_t first, const glm::dvec3& renderOrigin,
                    RayLanes& out, int* valid) {
  for (int k = 0; k < out.width; ++k) {
    const size_t i = first + size_t(k);
    const bool in = i < rays.size();
    const glm::dvec3 o = in ? rays.origin[i] - renderOrigin : glm::dvec3(0.0);
    const glm::dvec3 d = in ? rays.direction[i] : glm::dvec3(0.0, 0.0, 1.0);
    out.orgX[k] = float(o.x);
    out.orgY[k] = float(o.y);
    out.orgZ[k] = float(o.z);
    out.dirX[k] = float(d.x);
    out.dirY[k] = float(d.y);
    out.dirZ[k] = float(d.z);
    out.tnear[k] = in ? rays.tnear[i] : 0.0f;
    out.tfar[k] = in ? rays.tfar[i] : 0.0f;
    out.time[k] = 0.0f;
    out.mask[k] = 0xFFFFFFFFu;
    out.id[k] = unsigned(k);
    out.flags[k] = 0;
    valid[k] = in ? -1 : 0;
  }
}

std::vector<TraceRay> lidarTraceRays(const LidarRays& rays, const glm::dvec3& renderOrigin) {
  std::vector<TraceRay> out(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    out[i].org = glm::vec3(rays.origin[i] - renderOrigin);
    out[i].dir = glm::vec3(rays.direction[i]);
    out[i].tnear = rays.tnear[i];
    out[i].tfar = rays.tfar[i];
  }
  return out;
}

std::optional<double> applyRangeNoise(const RangeNoise& noise, double range, int sweep,
                                      uint64_t index) {
  if (!(noise.sigma >= 0) || !std::isfinite(noise.sigma))
    throw Error(cat("range noise sigma must be ≥ 0 metres, not ", noise.sigma));
  if (!(noise.dropout >= 0 && noise.dropout < 1))
    throw Error(cat("dropout probability must lie in [0, 1), not ", noise.dropout));
  if (!noise.enabled()) return range;
  if (noise.dropout > 0 && noiseUniform(noise.seed, sweep, index, 0) < noise.dropout)
    return std::nullopt;
  if (noise.sigma == 0) return range;
  // Box-Muller: u1 in (0, 1], u2 in [0, 1).
  const double u1 = 1.0 - noiseUniform(noise.seed, sweep, index, 1);
  const double u2 = noiseUniform(noise.seed, sweep, index, 2);
  const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
  return range + noise.sigma * z;
}

}  // namespace aperture
