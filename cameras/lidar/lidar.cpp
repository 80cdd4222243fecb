#include "cameras/lidar/lidar.h"

#include <algorithm>
#include <cmath>

#include "core/engine/packet.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace aperture {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// deg in [0, 360).
double wrap360(double deg) {
  double a = deg >= 0 && deg < 360.0 ? deg : std::fmod(deg, 360.0);
  if (a < 0) a += 360.0;
  return a >= 360.0 ? 0.0 : a;
}

float wrapDegrees(double deg) {
  const float f = float(wrap360(deg));
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

glm::dvec3 unitDirection(double azimuthDeg, double elevationDeg) {
  const double psi = azimuthDeg * kDeg, phi = elevationDeg * kDeg;
  return {std::cos(psi) * std::cos(phi), std::sin(psi) * std::cos(phi), std::sin(phi)};
}

// Rz(angle)·v for the angle's cosine c and sine s.
glm::dvec3 turned(double c, double s, const glm::dvec3& v) {
  return {c * v.x - s * v.y, s * v.x + c * v.y, v.z};
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
  const bool spinning = sensor.kind == LidarKind::Spinning;

  // The firing order: spinning, (column, beam) column by column; pattern, the table's rows of
  // the cycles that fall in this sweep (sweep k covers [k·P, (k+1)·P) of the pattern's clock,
  // which repeats every Q).
  std::vector<int> ids;
  std::vector<std::pair<size_t, int64_t>> patternRays;  // (table row, time in the sweep)
  size_t n = 0;
  if (spinning) {
    ids = sensor.windowColumns();
    out.rows = int(sensor.beams.size());
    out.columns = sensor.columns;
    n = ids.size() * sensor.beams.size();
  } else {
    const int64_t P = out.periodNs, Q = sensor.patternPeriodNs;
    const int64_t from = int64_t(sweep) * P, to = from + P;
    for (int64_t cycle = from / Q; cycle * Q < to; ++cycle)
      for (size_t r = 0; r < sensor.pattern.size(); ++r) {
        const int64_t g = cycle * Q + sensor.pattern[r].timeNs;
        if (g >= from && g < to) patternRays.emplace_back(r, g - from);
      }
    out.rows = 1;
    out.columns = int(patternRays.size());
    n = patternRays.size();
  }
  const size_t beams = spinning ? sensor.beams.size() : 1;
  auto timeOf = [&](size_t i) {
    return spinning ? sensor.columnTime(ids[i / beams]) + sensor.beams[i % beams].timeOffsetNs
                    : patternRays[i].second;
  };

  // Every firing time inside the trajectory, before any pose is taken: the earliest and the
  // latest (spinning: a column's time grows with its measurement id, which grows along the
  // window's firing order, and each beam adds its offset; pattern: the rays in order).
  if (n > 0) {
    int64_t lo = timeOf(0), hi = lo;
    if (spinning) {
      int64_t first = 0, last = 0;
      for (const LidarBeam& b : sensor.beams) {
        first = std::min(first, b.timeOffsetNs);
        last = std::max(last, b.timeOffsetNs);
      }
      const auto [earliest, latest] = std::minmax_element(ids.begin(), ids.end());
      lo = sensor.columnTime(*earliest) + first;
      hi = sensor.columnTime(*latest) + last;
    } else {
      for (size_t i = 1; i < n; ++i) {
        lo = std::min(lo, timeOf(i));
        hi = std::max(hi, timeOf(i));
      }
    }
    for (int64_t t : {lo, hi})
      if (!trajectory.covers(out.sweepStartNs + t))
        throw Error(cat(sensor.name, " sweep ", sweep, ": firing time ",
                        formatTimeNs(out.sweepStartNs + t), " s lies outside the trajectory ",
                        trajectory.source(), " (", formatTimeNs(trajectory.startNs()), " to ",
                        formatTimeNs(trajectory.endNs()), " s)"));
  }
  if (trajectory.covers(out.sweepStartNs))
    out.sweepStartPose = trajectory.at(out.sweepStartNs);
  else if (n > 0)
    out.sweepStartPose = trajectory.at(out.sweepStartNs + timeOf(0));

  // One pose per firing time: per column when every beam of a column fires at once.
  bool perBeam = false;
  if (spinning)
    for (const LidarBeam& b : sensor.beams) perBeam = perBeam || b.timeOffsetNs != 0;
  const size_t raysPerPose = spinning && !perBeam ? beams : 1;
  const size_t poseCount = n / raysPerPose;
  out.poses.resize(poseCount);
  std::vector<glm::dmat3> rotations(poseCount);
  std::vector<glm::dvec3> translations(poseCount);
  parallelFor(poseCount, 256, [&](size_t first, size_t last) {
    for (size_t k = first; k < last; ++k) {
      out.poses[k] = trajectory.at(out.sweepStartNs + timeOf(k * raysPerPose));
      const Pose worldFromLidar = out.poses[k] * sensorFromLidar;
      rotations[k] = glm::mat3_cast(worldFromLidar.rotation);
      translations[k] = worldFromLidar.translation;
    }
  });

  // Each beam's direction and origin at encoder angle 0, once.
  std::vector<glm::dvec3> beamDirection, beamOrigin;
  for (const LidarBeam& b : sensor.beams) {
    beamDirection.push_back(unitDirection(b.azimuthDeg, b.elevationDeg));
    beamOrigin.push_back(b.origin);
  }

  out.origin.resize(n);
  out.direction.resize(n);
  out.timeNs.resize(n);
  out.ring.resize(n);
  out.column.resize(n);
  out.azimuthDeg.resize(n);
  out.elevationDeg.resize(n);
  out.rangeOffset.resize(n);
  out.tnear.resize(n);
  out.tfar.resize(n);
  out.poseIndex.resize(n);
  // Every ray is a pure function of its index: the thread count changes nothing.
  const size_t unit = spinning ? beams : 1;
  parallelFor(n / unit, spinning ? 16 : 4096, [&](size_t first, size_t last) {
    for (size_t u = first; u < last; ++u) {
      double c = 1, s = 0, columnDeg = 0;
      int64_t columnNs = 0;
      if (spinning) {
        columnNs = sensor.columnTime(ids[u]);
        const double turn = sensor.columnAzimuthDeg(ids[u]);
        c = std::cos(turn * kDeg);
        s = std::sin(turn * kDeg);
        columnDeg = wrap360(turn);
      }
      for (size_t b = 0; b < unit; ++b) {
        const size_t i = u * unit + b;
        const size_t k = i / raysPerPose;
        glm::dvec3 d, o(0.0);
        double azimuth, elevation, rangeOffset = 0;
        if (spinning) {
          const LidarBeam& beam = sensor.beams[b];
          d = turned(c, s, beamDirection[b]);
          o = turned(c, s, beamOrigin[b]);
          azimuth = columnDeg + beam.azimuthDeg;
          elevation = beam.elevationDeg;
          rangeOffset = beam.rangeOffset;
          out.ring[i] = uint32_t(b);
          out.column[i] = uint32_t(ids[u]);
        } else {
          const PatternRay& p = sensor.pattern[patternRays[i].first];
          d = unitDirection(p.azimuthDeg, p.elevationDeg);
          azimuth = p.azimuthDeg;
          elevation = p.elevationDeg;
          out.ring[i] = 0;
          out.column[i] = uint32_t(i);
        }
        out.timeNs[i] = spinning ? columnNs + sensor.beams[b].timeOffsetNs : patternRays[i].second;
        out.poseIndex[i] = uint32_t(k);
        out.origin[i] = rotations[k] * o + translations[k];
        out.direction[i] = glm::normalize(rotations[k] * d);
        out.azimuthDeg[i] = wrapDegrees(azimuth);
        out.elevationDeg[i] = float(elevation);
        out.rangeOffset[i] = float(rangeOffset);
        out.tnear[i] = float(std::max(0.0, sensor.minRange - rangeOffset));
        out.tfar[i] = float(std::max(0.0, sensor.maxRange - rangeOffset));
      }
    }
  });
  return out;
}

void fillLidarLanes(const LidarRays& rays, size_t first, const glm::dvec3& renderOrigin,
                    RayLanes& out, int* valid) {
  for (int k = 0; k < out.width; ++k) {
    const size_t i = first + size_t(k);
    const bool in = i < rays.size();
    const glm::dvec3 o = in ? rays.origin[i] - renderOrigin : glm::dvec3(0.0);
    const glm::dvec3 d = in ? rays.direction[i] : glm::dvec3(0.0, 0.0, 1.0);
    const float ox = float(o.x), oy = float(o.y), oz = float(o.z);
    const float dx = float(d.x), dy = float(d.y), dz = float(d.z);
    const float tnear = in ? rays.tnear[i] : 1.0f, tfar = in ? rays.tfar[i] : 0.0f;
    // Sealed here, from the values in registers (sealLanes would read the lanes back right
    // after these scalar stores, each vector load waiting for the stores it spans).
    const int live = int(in) & traceableRay(ox, oy, oz, dx, dy, dz, tnear, tfar);
    out.orgX[k] = ox;
    out.orgY[k] = oy;
    out.orgZ[k] = oz;
    out.dirX[k] = dx;
    out.dirY[k] = dy;
    out.dirZ[k] = dz;
    out.tnear[k] = live ? tnear : 1.0f;
    out.tfar[k] = live ? tfar : 0.0f;
    out.time[k] = 0.0f;
    out.mask[k] = 0xFFFFFFFFu;
    out.id[k] = unsigned(k);
    out.flags[k] = 0;
    valid[k] = -live;
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
