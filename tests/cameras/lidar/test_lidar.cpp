// One sweep's rays traced in a closed box room built by hand: ranges against the analytic
// distance to the wall, the elevation histogram against the beam table, every beam × column
// once, firing times, a moving sensor against poses interpolated here, and range noise.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/gtc/quaternion.hpp>
#include <limits>
#include <map>
#include <set>

#include "cameras/lidar/lidar.h"
#include "core/engine/packet.h"
#include "core/queries/trace.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "tests/lidar_support.h"

namespace aperture {
namespace {

constexpr double kPiLidar = 3.14159265358979323846;

// Sixteen beams at uneven elevations, some with azimuth offsets, 360 columns at 10 Hz.
LidarSensor unevenSixteen() {
  return loadLidarText(R"({"name": "uneven", "sweep_rate_hz": 10, "columns": 360,
    "beams": {"elevation_deg": [-25, -15.5, -9, -6.25, -4, -2.5, -1, 0, 0.75, 1.5, 3, 5, 8, 11.5,
                                15, 22],
              "azimuth_deg": [0, 1.5, 0, -1.5, 0, 1.5, 0, -1.5, 0, 1.5, 0, -1.5, 0, 1.5, 0, -1.5]}})",
                       "uneven.json");
}

std::vector<TraceHit> traceSweep(const test::BoxRoom& room, const LidarRays& rays) {
  return traceRays(*room.scene, lidarTraceRays(rays, room.scene->renderOrigin()), 16);
}

TEST(LidarSweep, RangesInABoxRoomAreTheAnalyticDistance) {
  const glm::dvec3 centre(120.0, -40.0, 7.5);
  const test::BoxRoom room = test::makeBoxRoom({5.0, 4.0, 3.0}, centre);
  Pose atCentre;
  atCentre.translation = centre;
  for (const std::string& name :
       {std::string("uneven"), std::string("OS1-64"), std::string("VLP-16")}) {
    SCOPED_TRACE(name);
    const LidarSensor s = name == "uneven" ? unevenSixteen() : loadLidar(name);
    const LidarRays rays = sweepRays(s, Trajectory(atCentre), 0);
    const std::vector<TraceHit> hits = traceSweep(room, rays);
    ASSERT_EQ(hits.size(), rays.size());
    double worst = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      ASSERT_TRUE(hits[i].hit()) << "ray " << i << " left the closed room";
      const double range = double(hits[i].t) + rays.rangeOffset[i];
      const double expected =
          test::boxExitDistance(room, rays.origin[i], rays.direction[i]) + rays.rangeOffset[i];
      worst = std::max(worst, std::fabs(range - expected) / expected);
    }
    EXPECT_LE(worst, 1e-5);
  }
}

TEST(LidarSweep, EveryBeamAndColumnOnceAndTheElevationPeaksAreTheTable) {
  const test::BoxRoom room = test::makeBoxRoom({5.0, 4.0, 3.0});
  const LidarSensor s = unevenSixteen();
  const LidarRays rays = sweepRays(s, Trajectory(), 0);
  const std::vector<TraceHit> hits = traceSweep(room, rays);
  ASSERT_EQ(rays.size(), s.beams.size() * size_t(s.columns));

  std::set<std::pair<uint32_t, uint32_t>> seen;
  std::map<long, int> histogram;  // elevation of each point in 0.001° bins
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_TRUE(hits[i].hit());
    EXPECT_TRUE(seen.insert({rays.ring[i], rays.column[i]}).second)
        << "ring " << rays.ring[i] << " column " << rays.column[i] << " twice";
    // The point as the sensor reports it, its elevation seen from the sensor's origin.
    const glm::dvec3 p = rays.sensorPointAt(i, hits[i].t);
    const double elevation = std::atan2(p.z, std::hypot(p.x, p.y)) * 180 / kPiLidar;
    ++histogram[std::lround(elevation * 1000)];
  }
  EXPECT_EQ(seen.size(), s.beams.size() * size_t(s.columns));
  ASSERT_EQ(histogram.size(), s.beams.size());
  auto peak = histogram.begin();
  std::vector<double> table;
  for (const LidarBeam& b : s.beams) table.push_back(b.elevationDeg);
  std::sort(table.begin(), table.end());
  for (double e : table) {
    EXPECT_EQ(peak->first, std::lround(e * 1000));
    EXPECT_EQ(peak->second, s.columns);
    ++peak;
  }
}

TEST(LidarSweep, FiringTimesIncreaseAndSpanTheSweep) {
  for (const std::string& name : {std::string("VLP-16"), std::string("OS1-128")}) {
    SCOPED_TRACE(name);
    const LidarSensor s = loadLidar(name);
    const LidarRays rays = sweepRays(s, Trajectory(), 0);
    ASSERT_EQ(rays.size(), s.beams.size() * size_t(s.columns));
    EXPECT_EQ(rays.timeNs.front(), 0);
    for (size_t i = 1; i < rays.size(); ++i) {
      ASSERT_GE(rays.timeNs[i], rays.timeNs[i - 1]) << "ray " << i;
      ASSERT_GE(rays.column[i], rays.column[i - 1]);
    }
    // The last column fires within the last column's slot of the period.
    const int64_t last = rays.timeNs.back();
    EXPECT_LT(last, s.periodNs());
    EXPECT_GE(last, s.periodNs() - 2 * s.periodNs() / s.columns);
    // Each column's beams at the column's time plus their own offsets.
    for (size_t i = 0; i < rays.size(); i += 101)
      EXPECT_EQ(rays.timeNs[i],
                s.columnTime(int(rays.column[i])) + s.beams[rays.ring[i]].timeOffsetNs);
  }
  const LidarSensor os = loadLidar("OS1-64");
  const LidarRays r = sweepRays(os, Trajectory(), 0);
  // Ouster: every beam of a column at once, column m at m·period/columns.
  EXPECT_EQ(r.timeNs[64 * 512], 512 * os.periodNs() / 1024);
  EXPECT_EQ(r.timeNs[64 * 512 + 63], r.timeNs[64 * 512]);
}

// The pose at time `ns` of a two-row trajectory, interpolated here with GLM (independently of
// Trajectory::at).
Pose poseBetween(const TimedPose& a, const TimedPose& b, int64_t ns) {
  const double f = double(ns - a.timeNs) / double(b.timeNs - a.timeNs);
  Pose p;
  p.translation = glm::mix(a.pose.translation, b.pose.translation, f);
  p.rotation = glm::slerp(a.pose.rotation, b.pose.rotation, f);
  return p;
}

TEST(LidarSweep, AMovingSensorsPointsLieWhereTheirRaysHitFromTheirOwnPose) {
  const glm::dvec3 centre(30.0, 12.0, -4.0);
  const test::BoxRoom room = test::makeBoxRoom({6.0, 5.0, 3.0}, centre);
  TimedPose a, b;
  a.timeNs = 1700000000000000000LL;  // a Unix time: nanoseconds stay exact
  b.timeNs = a.timeNs + 200000000;
  a.pose.translation = centre + glm::dvec3(-1.0, -0.6, -0.2);
  b.pose.translation = centre + glm::dvec3(1.0, 0.6, 0.3);
  a.pose.rotation = glm::angleAxis(-0.2, glm::dvec3(0, 0, 1));
  b.pose.rotation = glm::angleAxis(0.6, glm::normalize(glm::dvec3(0.1, 0.05, 1)));
  const Trajectory trajectory({a, b}, "two poses");

  const LidarSensor s = loadLidar("OS1-64");
  const Pose sensorFromLidar = Pose::fromMatrix(s.sensorFromLidar);
  const LidarRays rays = sweepRays(s, trajectory, 1);
  EXPECT_EQ(rays.sweepStartNs, a.timeNs + s.periodNs());
  const std::vector<TraceHit> hits = traceSweep(room, rays);
  double worstDistance = 0, worstExpected = 0, worstRoundTrip = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_TRUE(hits[i].hit());
    const glm::dvec3 p = rays.origin[i] + rays.direction[i] * double(hits[i].t);
    EXPECT_TRUE(test::onBoxWall(room, p, 1e-4)) << "ray " << i;

    // The same beam fired from the pose at the ray's own time, built here.
    const Pose pose = poseBetween(a, b, rays.sweepStartNs + rays.timeNs[i]);
    const LidarBeam& beam = s.beams[rays.ring[i]];
    const double psiC = -double(rays.column[i]) * 360.0 / s.columns * kPiLidar / 180;
    const double psi = psiC + beam.azimuthDeg * kPiLidar / 180;
    const double phi = beam.elevationDeg * kPiLidar / 180;
    const glm::dvec3 dLidar(std::cos(psi) * std::cos(phi), std::sin(psi) * std::cos(phi),
                            std::sin(phi));
    const glm::dvec3 oLidar(std::cos(psiC) * beam.origin.x, std::sin(psiC) * beam.origin.x,
                            beam.origin.z);
    const Pose worldFromLidar = pose * sensorFromLidar;
    const glm::dvec3 o = worldFromLidar.apply(oLidar);
    const glm::dvec3 d = worldFromLidar.applyDirection(dLidar);
    const glm::dvec3 expected = o + d * test::boxExitDistance(room, o, d);
    worstExpected = std::max(worstExpected, glm::length(p - expected));

    // The reported point (sensor frame at fire time) taken back through that pose.
    const glm::dvec3 q = rays.sensorPointAt(i, hits[i].t);
    worstRoundTrip = std::max(worstRoundTrip, glm::length(pose.apply(q) - p));
    worstDistance = std::max(
        worstDistance,
        std::fabs(glm::length(q - glm::dvec3(sensorFromLidar.apply(oLidar))) - double(hits[i].t)));
  }
  EXPECT_LE(worstExpected, 1e-4);
  EXPECT_LE(worstRoundTrip, 1e-4);
  EXPECT_LE(worstDistance, 1e-4);
  // The sensor moved during the sweep: its first and last poses differ.
  EXPECT_GT(glm::length(rays.poses.front().translation - rays.poses.back().translation), 0.4);
}

TEST(LidarSweep, SweepStartsAndTimesOutsideTheTrajectory) {
  TimedPose a, b;
  a.timeNs = 5000000000LL;
  b.timeNs = a.timeNs + 250000000;
  b.pose.translation = {1, 0, 0};
  const Trajectory trajectory({a, b}, "short.txt");
  const LidarSensor s = unevenSixteen();
  EXPECT_EQ(sweepRays(s, trajectory, 1).sweepStartNs, a.timeNs + 100000000);
  EXPECT_EQ(sweepRays(s, trajectory, 0, a.timeNs + 123).sweepStartNs, a.timeNs + 123);
  try {
    sweepRays(s, trajectory, 2);
    FAIL() << "sweep 2 ends after the trajectory";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("short.txt"), std::string::npos) << m;
    EXPECT_NE(m.find("5.2"), std::string::npos) << m;
    EXPECT_NE(m.find("outside the trajectory"), std::string::npos) << m;
  }
  EXPECT_THROW(sweepRays(s, trajectory, 0, a.timeNs - 1), Error);
}

TEST(LidarSweep, PatternSweepsContinueThePattern) {
  const LidarSensor s = loadLidarText(R"({"name": "rosette", "sweep_rate_hz": 100,
    "pattern": [[0, 0, 0], [0.001, 120, 10], [0.002, 240, -10]], "pattern_period_s": 0.003})",
                                      "rosette.json");
  EXPECT_EQ(s.kind, LidarKind::Pattern);
  const LidarRays first = sweepRays(s, Trajectory(), 0), second = sweepRays(s, Trajectory(), 1);
  // 10 ms sweeps of a 1 ms clock: rays at 0..9 ms, then 10..19 ms of the pattern's clock.
  ASSERT_EQ(first.size(), 10u);
  ASSERT_EQ(second.size(), 10u);
  for (size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(first.timeNs[i], int64_t(i) * 1000000);
    EXPECT_EQ(second.timeNs[i], int64_t(i) * 1000000);
    EXPECT_EQ(first.column[i], i);
    EXPECT_EQ(first.ring[i], 0u);
    EXPECT_NEAR(first.azimuthDeg[i], float((i % 3) * 120), 1e-4);
    EXPECT_NEAR(second.azimuthDeg[i], float(((i + 10) % 3) * 120), 1e-4);
  }
}

TEST(LidarSweep, PacketLanesAreTheTraceRays) {
  const LidarSensor s = unevenSixteen();
  Pose pose;
  pose.translation = {1000.25, -3.5, 2};
  const LidarRays rays = sweepRays(s, Trajectory(pose), 0);
  const glm::dvec3 renderOrigin(1000, 0, 0);
  const std::vector<TraceRay> trace = lidarTraceRays(rays, renderOrigin);
  float ox[16], oy[16], oz[16], tn[16], dx[16], dy[16], dz[16], tm[16], tf[16];
  unsigned mask[16], id[16], flags[16];
  int valid[16];
  RayLanes lanes{16, ox, oy, oz, tn, dx, dy, dz, tm, tf, mask, id, flags};
  const size_t first = rays.size() - 5;  // a packet past the end
  fillLidarLanes(rays, first, renderOrigin, lanes, valid);
  for (int k = 0; k < 16; ++k) {
    const size_t i = first + size_t(k);
    if (i >= rays.size()) {
      EXPECT_EQ(valid[k], 0);
      EXPECT_TRUE(std::isfinite(ox[k]) && std::isfinite(dx[k]));
      continue;
    }
    EXPECT_EQ(valid[k], -1);
    EXPECT_EQ(glm::vec3(ox[k], oy[k], oz[k]), trace[i].org);
    EXPECT_EQ(glm::vec3(dx[k], dy[k], dz[k]), trace[i].dir);
    EXPECT_EQ(tn[k], trace[i].tnear);
    EXPECT_EQ(tf[k], trace[i].tfar);
  }
  // A ray Embree cannot take is sealed as sealLanes seals it: inactive, the empty segment.
  LidarRays bad = rays;
  bad.direction[first].x = std::numeric_limits<double>::quiet_NaN();
  bad.tfar[first + 1] = bad.tnear[first + 1] - 1.0f;
  fillLidarLanes(bad, first, renderOrigin, lanes, valid);
  for (int k : {0, 1}) {
    EXPECT_EQ(valid[k], 0) << k;
    EXPECT_EQ(tn[k], 1.0f) << k;
    EXPECT_EQ(tf[k], 0.0f) << k;
  }
  EXPECT_EQ(valid[2], -1);
  int sealed[16];
  std::copy(valid, valid + 16, sealed);
  sealLanes<16>(sealed, lanes);
  EXPECT_TRUE(std::equal(valid, valid + 16, sealed));
}

// Noisy ranges of rays [0, n) computed on `threads` threads.
std::vector<double> noisyRanges(const RangeNoise& noise, size_t n, int threads) {
  std::vector<double> out(n);
  tbb::task_arena arena(threads);
  arena.execute([&] {
    parallelFor(n, 4096, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        const std::optional<double> r = applyRangeNoise(noise, 10.0, 3, i);
        out[i] = r ? *r : -1.0;
      }
    });
  });
  return out;
}

TEST(LidarNoise, SameSeedSameRangesOnAnyThreadCountAndSigmaHolds) {
  RangeNoise noise;
  EXPECT_EQ(*applyRangeNoise(noise, 12.345, 0, 7), 12.345);  // off by default
  noise.sigma = 0.02;
  noise.seed = 42;
  const size_t n = 1000000;
  const std::vector<double> one = noisyRanges(noise, n, 1), two = noisyRanges(noise, n, 2);
  EXPECT_EQ(std::memcmp(one.data(), two.data(), n * sizeof(double)), 0);
  double sum = 0, sum2 = 0;
  for (double r : one) {
    sum += r - 10.0;
    sum2 += (r - 10.0) * (r - 10.0);
  }
  const double mean = sum / double(n), sd = std::sqrt(sum2 / double(n) - mean * mean);
  EXPECT_NEAR(sd, noise.sigma, 0.05 * noise.sigma);
  EXPECT_NEAR(mean, 0.0, 5 * noise.sigma / std::sqrt(double(n)));

  RangeNoise other = noise;
  other.seed = 43;
  EXPECT_NE(noisyRanges(other, 1000, 1), std::vector<double>(one.begin(), one.begin() + 1000));

  noise.dropout = 0.1;
  const std::vector<double> dropped = noisyRanges(noise, n, 2);
  const double fraction = double(std::count(dropped.begin(), dropped.end(), -1.0)) / double(n);
  EXPECT_NEAR(fraction, 0.1, 0.003);
  EXPECT_EQ(dropped, noisyRanges(noise, n, 1));

  noise.dropout = 1.0;
  EXPECT_THROW(applyRangeNoise(noise, 1.0, 0, 0), Error);
  noise.dropout = 0;
  noise.sigma = -1;
  EXPECT_THROW(applyRangeNoise(noise, 1.0, 0, 0), Error);
}

}  // namespace
}  // namespace aperture
