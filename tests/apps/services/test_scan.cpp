// The scan loop (apps/services/scan.h) in a closed box room, with rays made here from a beam
// table (independently of cameras/lidar's sweepRays): every range equals the analytic distance
// to the wall the ray meets, the elevations of the cloud are exactly the beam table's, every
// beam × column ray is present once, intensity follows its documented model, points of a
// moving sensor land on the walls, range limits and noise behave, and multiple surfaces come
// back as first, last and all returns.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "apps/services/render_options.h"
#include "apps/services/scan.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/mesh/ply.h"
#include "core/points/point_writers.h"
#include "core/queries/trace.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture::app {
namespace {

namespace pf = point_fields;

constexpr double kLo[3] = {-2.0, -1.5, -1.0}, kHi[3] = {3.0, 2.0, 1.25};

/// An ASCII PLY of the box [kLo, kHi] (12 triangles) with face properties "semantic" (the wall:
/// 0 -x, 1 +x, 2 -y, 3 +y, 4 -z, 5 +z) and "reflectance" (percent: 10·(wall + 1)), and
/// `panes` squares at x = 1, 1.001, 1.002, ... (y, z in [-1, 1]) of wall 6.
std::string boxRoomPly(int panes) {
  std::vector<std::array<double, 3>> v;
  std::vector<std::array<int, 4>> f;  // a, b, c, wall
  auto quad = [&](std::array<double, 3> a, std::array<double, 3> b, std::array<double, 3> c,
                  std::array<double, 3> d, int wall) {
    const int base = int(v.size());
    v.insert(v.end(), {a, b, c, d});
    f.push_back({base, base + 1, base + 2, wall});
    f.push_back({base, base + 2, base + 3, wall});
  };
  const double x0 = kLo[0], x1 = kHi[0], y0 = kLo[1], y1 = kHi[1], z0 = kLo[2], z1 = kHi[2];
  quad({x0, y0, z0}, {x0, y1, z0}, {x0, y1, z1}, {x0, y0, z1}, 0);
  quad({x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}, 1);
  quad({x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}, 2);
  quad({x0, y1, z0}, {x1, y1, z0}, {x1, y1, z1}, {x0, y1, z1}, 3);
  quad({x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0}, 4);
  quad({x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}, 5);
  for (int k = 0; k < panes; ++k) {
    const double x = 1 + 0.001 * k;
    quad({x, -1, -1}, {x, 1, -1}, {x, 1, 1}, {x, -1, 1}, 6);
  }
  std::string s =
      cat("ply\nformat ascii 1.0\nelement vertex ", v.size(),
          "\nproperty double x\nproperty double y\nproperty double z\nelement face ", f.size(),
          "\nproperty list uchar int vertex_indices\nproperty uint semantic\n"
          "property uint reflectance\nend_header\n");
  for (const auto& p : v) s += cat(p[0], " ", p[1], " ", p[2], "\n");
  for (const auto& t : f)
    s += cat("3 ", t[0], " ", t[1], " ", t[2], " ", t[3], " ", 10 * (t[3] + 1), "\n");
  return s;
}

struct BoxRoom {
  Device device;
  Mesh mesh;
  std::unique_ptr<Scene> scene;
  /// `contextFilter`: the BVH the layers' Filter method needs (without it, Retrace).
  explicit BoxRoom(int panes = 0, bool contextFilter = false) {
    const std::string ply = boxRoomPly(panes);
    LoadOptions o;
    o.properties = {{PropertyDomain::Face, "semantic"}, {PropertyDomain::Face, "reflectance"}};
    mesh = loadPlyFromMemory(ply.data(), ply.size(), "box.ply", o);
    finishMesh(mesh, o);
    BuildOptions b;
    b.contextFilter = contextFilter;
    scene = std::make_unique<Scene>(device, std::vector<const Mesh*>{&mesh}, b);
  }
};

const std::vector<double> kElevations = {15.0, 7.5, 2.0, 0.0, -3.25, -11.0, -24.0};

LidarSensor roomSensor(int columns) {
  LidarSensor s;
  s.name = "room";
  s.source = {"room (test)", "aperture"};
  for (double e : kElevations) {
    LidarBeam b;
    b.elevationDeg = e;
    s.beams.push_back(b);
  }
  s.columns = columns;
  s.sweepRateHz = 10;
  s.pixelShiftByRow = {0, 1, 2, 3, -1, -2, -3};
  return s;
}

/// The sweep's rays made here: column m at azimuth m·360/columns (counter-clockwise), firing
/// at m·period/columns; every beam of a column at once. The sensor's pose at each column's
/// time is `poseAt(t)` (worldFromSensor), the sensor frame equal to the lidar frame.
template <class PoseAt>
LidarRays roomRays(const LidarSensor& s, PoseAt poseAt) {
  LidarRays r;
  r.periodNs = 100000000;
  r.rows = int(s.beams.size());
  r.columns = s.columns;
  r.sweepStartPose = poseAt(0);
  for (int m = 0; m < s.columns; ++m) {
    const int64_t t = int64_t(m) * r.periodNs / s.columns;
    r.poses.push_back(poseAt(t));
    for (size_t b = 0; b < s.beams.size(); ++b) {
      const double psi = glm::radians(360.0 * m / s.columns);
      const double phi = glm::radians(s.beams[b].elevationDeg);
      const glm::dvec3 local(std::cos(psi) * std::cos(phi), std::sin(psi) * std::cos(phi),
                             std::sin(phi));
      r.origin.push_back(r.poses.back().apply(glm::dvec3(0.0)));
      r.direction.push_back(r.poses.back().applyDirection(local));
      r.timeNs.push_back(t);
      r.ring.push_back(uint32_t(b));
      r.column.push_back(uint32_t(m));
      r.azimuthDeg.push_back(float(360.0 * m / s.columns));
      r.elevationDeg.push_back(float(s.beams[b].elevationDeg));
      r.rangeOffset.push_back(0.0f);
      r.tnear.push_back(float(s.minRange));
      r.tfar.push_back(float(s.maxRange));
      r.poseIndex.push_back(uint32_t(r.poses.size() - 1));
    }
  }
  return r;
}

LidarRays staticRoomRays(const LidarSensor& s) {
  return roomRays(s, [](int64_t) { return Pose{}; });
}

/// Distance from the origin along unit `d` to the box's wall, and that wall; `edge` tells a ray
/// that meets an edge of the room (two walls within 1e-6 relative), whose wall is ambiguous.
double wallDistance(const glm::dvec3& d, int* wall = nullptr, bool* edge = nullptr) {
  double best = 1e300, second = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) continue;
    const double t = (d[a] > 0 ? kHi[a] : kLo[a]) / d[a];
    if (t < best) {
      second = best;
      best = t;
      if (wall) *wall = 2 * a + (d[a] > 0 ? 1 : 0);
    } else {
      second = std::min(second, t);
    }
  }
  if (edge) *edge = second - best <= 1e-6 * best;
  return best;
}

template <typename T>
const T* fieldOf(const PointCloud& c, const char* name) {
  const PointField* f = c.find(name);
  EXPECT_NE(f, nullptr) << name;
  return f ? f->as<T>() : nullptr;
}

TEST(Scan, BoxRoomRangesAreAnalyticAndEveryRayIsThereOnce) {
  BoxRoom room;
  const LidarSensor sensor = roomSensor(720);
  const LidarRays rays = staticRoomRays(sensor);
  ScanOptions o;
  o.faceProperties = {"semantic"};
  const ScanSweep sweep = scanSweep(*room.scene, sensor, rays, o, true);
  const PointCloud& c = sweep.cloud;
  ASSERT_EQ(c.size, rays.size());
  const float* x = fieldOf<float>(c, pf::kX);
  const float* y = fieldOf<float>(c, pf::kY);
  const float* z = fieldOf<float>(c, pf::kZ);
  const float* range = fieldOf<float>(c, pf::kRange);
  const uint16_t* ring = fieldOf<uint16_t>(c, pf::kRing);
  const uint32_t* column = fieldOf<uint32_t>(c, pf::kColumn);
  const uint32_t* semantic = fieldOf<uint32_t>(c, "semantic");
  const float* intensity = fieldOf<float>(c, pf::kIntensity);
  const float* incidence = fieldOf<float>(c, pf::kIncidence);
  const uint32_t* time = fieldOf<uint32_t>(c, pf::kTime);
  std::set<std::pair<int, int>> seen;
  std::map<double, int> elevations;
  double worst = 0;
  for (size_t i = 0; i < c.size; ++i) {
    EXPECT_TRUE(seen.insert({ring[i], int(column[i])}).second) << "ray twice: " << i;
    const double psi = glm::radians(360.0 * column[i] / 720);
    const double phi = glm::radians(kElevations[ring[i]]);
    const glm::dvec3 d(std::cos(psi) * std::cos(phi), std::sin(psi) * std::cos(phi), std::sin(phi));
    int wall = -1;
    bool edge = false;
    const double expected = wallDistance(d, &wall, &edge);
    worst = std::max(worst, std::fabs(range[i] - expected) / expected);
    // The elevation histogram: asin(z / range), rounded to a thousandth of a degree.
    const double r = std::sqrt(double(x[i]) * x[i] + double(y[i]) * y[i] + double(z[i]) * z[i]);
    ++elevations[std::round(glm::degrees(std::asin(double(z[i]) / r)) * 1000.0) / 1000.0];
    if (edge) continue;
    EXPECT_EQ(semantic[i], uint32_t(wall)) << i;
    // Intensity: reflectance (percent of the wall) · cos(incidence) / range².
    const double cosine = std::fabs(d[wall / 2]);
    EXPECT_NEAR(incidence[i], cosine, 1e-5) << i;
    EXPECT_NEAR(intensity[i], 0.1 * (wall + 1) * cosine / (expected * expected),
                1e-5 * intensity[i] + 1e-7)
        << i;
    EXPECT_EQ(time[i], uint32_t(int64_t(column[i]) * 100000000 / 720));
  }
  EXPECT_LE(worst, 1e-5);
  EXPECT_EQ(seen.size(), sensor.beams.size() * 720u);
  ASSERT_EQ(elevations.size(), kElevations.size());
  for (double e : kElevations) EXPECT_EQ(elevations[e], 720) << e;

  // The range image: RANGE in millimetres at (ring, column), its destagger a roll by row.
  const RangeImage& img = sweep.image;
  EXPECT_EQ(img.rows, 7);
  EXPECT_EQ(img.columns, 720);
  const uint32_t* RANGE = img.find("RANGE")->as<uint32_t>();
  for (size_t i = 0; i < c.size; ++i)
    EXPECT_EQ(RANGE[size_t(ring[i]) * 720 + column[i]], uint32_t(std::lround(range[i] * 1000.0)));
}

TEST(Scan, RangeLimitsDropPointsAndZeroPixels) {
  BoxRoom room;
  LidarSensor sensor = roomSensor(360);
  sensor.minRange = 1.2;
  sensor.maxRange = 2.5;
  LidarRays rays = staticRoomRays(sensor);
  const ScanSweep sweep = scanSweep(*room.scene, sensor, rays, {}, true);
  size_t inside = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const double d = wallDistance(rays.direction[i]);
    inside += d >= 1.2 && d <= 2.5 ? 1 : 0;
  }
  EXPECT_EQ(sweep.cloud.size, inside);
  EXPECT_GT(inside, 0u);
  EXPECT_LT(inside, rays.size());
  const float* range = fieldOf<float>(sweep.cloud, pf::kRange);
  for (size_t i = 0; i < sweep.cloud.size; ++i) {
    EXPECT_GE(range[i], 1.2f);
    EXPECT_LE(range[i], 2.5f);
  }
  size_t zeros = 0;
  const uint32_t* RANGE = sweep.image.find("RANGE")->as<uint32_t>();
  for (int p = 0; p < sweep.image.rows * sweep.image.columns; ++p) zeros += RANGE[p] == 0 ? 1 : 0;
  EXPECT_EQ(zeros, rays.size() - inside);
}

TEST(Scan, ARayPastTheTimeFieldOrBeforeTheSweepIsRefusedByName) {
  BoxRoom room;
  const LidarSensor sensor = roomSensor(3000);  // 21000 rays: past the first chunk of 4096
  for (const int64_t bad : {int64_t(UINT32_MAX) + 1, int64_t(-1)}) {
    LidarRays rays = staticRoomRays(sensor);
    const size_t late = rays.size() - 7;
    rays.timeNs[late] = bad;
    try {
      scanSweep(*room.scene, sensor, rays, {});
      FAIL() << "a ray firing at " << bad << " ns was taken";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(cat("ray ", late, " fires ", bad, " ns")), std::string::npos) << what;
      EXPECT_NE(what.find("room (test)"), std::string::npos) << what;
    }
  }
  // The last time the field holds is taken.
  LidarRays rays = staticRoomRays(sensor);
  rays.timeNs.back() = int64_t(UINT32_MAX);
  const ScanSweep sweep = scanSweep(*room.scene, sensor, rays, {});
  EXPECT_EQ(fieldOf<uint32_t>(sweep.cloud, pf::kTime)[sweep.cloud.size - 1], UINT32_MAX);
}

TEST(Scan, MovingSensorPointsLandOnTheWallsThroughTheirOwnPose) {
  BoxRoom room;
  const LidarSensor sensor = roomSensor(360);
  // Moves 0.8 m along x and turns 30° about z during the sweep.
  auto poseAt = [](int64_t t) {
    const double s = double(t) / 1e8;
    Pose p;
    p.translation = glm::dvec3(-0.4 + 0.8 * s, 0.3 * s, 0.1);
    p.rotation = glm::angleAxis(glm::radians(30.0 * s), glm::dvec3(0, 0, 1));
    return p;
  };
  const LidarRays rays = roomRays(sensor, poseAt);
  for (ScanFrame frame : {ScanFrame::Sensor, ScanFrame::World, ScanFrame::SweepStart}) {
    ScanOptions o;
    o.frame = frame;
    const ScanSweep sweep = scanSweep(*room.scene, sensor, rays, o);
    const PointCloud& c = sweep.cloud;
    ASSERT_EQ(c.size, rays.size());
    const PointField *x = c.find(pf::kX), *y = c.find(pf::kY), *z = c.find(pf::kZ);
    const uint32_t* time = fieldOf<uint32_t>(c, pf::kTime);
    double worst = 0;
    for (size_t i = 0; i < c.size; ++i) {
      const glm::dvec3 p(x->value(i), y->value(i), z->value(i));
      const glm::dvec3 world = frame == ScanFrame::Sensor  ? poseAt(time[i]).apply(p)
                               : frame == ScanFrame::World ? p
                                                           : poseAt(0).apply(p);
      double gap = 1e300;
      for (int a = 0; a < 3; ++a)
        gap = std::min({gap, std::fabs(world[a] - kLo[a]), std::fabs(world[a] - kHi[a])});
      worst = std::max(worst, gap);
      if (i > 0) {
        EXPECT_GE(time[i], time[i - 1]);
      }
    }
    EXPECT_LE(worst, 1e-4) << scanFrameName(frame);
    EXPECT_EQ(time[0], 0u);
    EXPECT_EQ(time[c.size - 1], uint32_t(359 * int64_t(100000000) / 360));
    EXPECT_EQ(x->type, frame == ScanFrame::World ? PointType::Float64 : PointType::Float32);
  }
}

TEST(Scan, SurfacesAlongARayAsFirstLastStrongestAndAll) {
  BoxRoom room(1);  // a pane at x = 1 in front of the +x wall at x = 3
  const LidarSensor sensor = roomSensor(360);
  const LidarRays rays = staticRoomRays(sensor);
  auto run = [&](ScanReturns returns) {
    ScanOptions o;
    o.returns = returns;
    o.maxSurfaces = returns == ScanReturns::First ? 1 : 4;
    o.faceProperties = {"semantic"};
    return scanSweep(*room.scene, sensor, rays, o).cloud;
  };
  const PointCloud first = run(ScanReturns::First), last = run(ScanReturns::Last),
                   strongest = run(ScanReturns::Strongest), all = run(ScanReturns::All);
  ASSERT_EQ(first.size, rays.size());
  ASSERT_EQ(last.size, rays.size());
  ASSERT_EQ(strongest.size, rays.size());
  size_t throughPane = 0, rim = 0;
  const uint32_t* f = fieldOf<uint32_t>(first, "semantic");
  const uint32_t* l = fieldOf<uint32_t>(last, "semantic");
  const float* fi = fieldOf<float>(first, pf::kIntensity);
  const float* li = fieldOf<float>(last, pf::kIntensity);
  const float* si = fieldOf<float>(strongest, pf::kIntensity);
  for (size_t i = 0; i < rays.size(); ++i) {
    const glm::dvec3 d = rays.direction[i];
    // Through the pane (x = 1, |y|, |z| <= 1); rays within 1e-6 of its rim are left out.
    const double py = d.x > 0 ? std::fabs(d.y / d.x) : 2, pz = d.x > 0 ? std::fabs(d.z / d.x) : 2;
    const bool pane = py < 1 && pz < 1;
    bool edge = false;
    wallDistance(d, nullptr, &edge);
    if (edge || std::fabs(py - 1) < 1e-6 || std::fabs(pz - 1) < 1e-6) {
      ++rim;
      continue;
    }
    if (pane) {
      ++throughPane;
      EXPECT_EQ(f[i], 6u) << i;
      EXPECT_NE(l[i], 6u) << i;
    } else {
      EXPECT_EQ(f[i], l[i]) << i;
    }
    EXPECT_EQ(si[i], std::max(fi[i], li[i])) << i;
  }
  EXPECT_GT(throughPane, 0u);
  EXPECT_GE(all.size, rays.size() + throughPane);
  EXPECT_LE(all.size, rays.size() + throughPane + rim);
  const uint8_t* number = fieldOf<uint8_t>(all, pf::kReturnNumber);
  const uint8_t* count = fieldOf<uint8_t>(all, pf::kReturns);
  size_t seconds = 0;
  for (size_t i = 0; i < all.size; ++i) {
    EXPECT_LE(number[i], count[i]);
    seconds += number[i] == 2 ? 1 : 0;
  }
  EXPECT_GE(seconds, throughPane);
  EXPECT_LE(seconds, throughPane + rim);
}

/// The surfaces along ray i found independently of the scan loop, by tracing again and again
/// with traceRays: the nearest hit, then the nearest at or past max(nextafter(t), t + sep).
std::vector<TraceHit> retracedSurfaces(const Scene& scene, const LidarRays& rays, size_t i,
                                       int surfaces, float sep) {
  TraceRay r;
  r.org = glm::vec3(rays.origin[i] - scene.renderOrigin());
  r.dir = glm::vec3(rays.direction[i]);
  r.tnear = rays.tnear[i];
  r.tfar = rays.tfar[i];
  std::vector<TraceHit> out;
  while (int(out.size()) < surfaces && r.tnear <= r.tfar) {
    const TraceHit h = traceRays(scene, {r}, 1)[0];
    if (!h.hit()) break;
    out.push_back(h);
    r.tnear = std::max(std::nextafter(h.t, std::numeric_limits<float>::infinity()), h.t + sep);
  }
  return out;
}

TEST(Scan, MultiReturnsThroughTheLayersAreTheAnalyticSurfacesAndTheRetracedOnes) {
  for (bool contextFilter : {true, false}) {  // the layers' Filter method, and Retrace
    BoxRoom room(1, contextFilter);           // a pane at x = 1 in front of the +x wall at x = 3
    const LidarSensor sensor = roomSensor(360);
    const LidarRays rays = staticRoomRays(sensor);
    ScanOptions o;
    o.returns = ScanReturns::All;
    o.maxSurfaces = 4;
    o.faceProperties = {"semantic"};
    const PointCloud all = scanSweep(*room.scene, sensor, rays, o).cloud;
    const float* range = fieldOf<float>(all, pf::kRange);
    const uint32_t* primid = fieldOf<uint32_t>(all, pf::kPrimId);
    const uint32_t* semantic = fieldOf<uint32_t>(all, "semantic");
    const uint8_t* number = fieldOf<uint8_t>(all, pf::kReturnNumber);
    const uint8_t* count = fieldOf<uint8_t>(all, pf::kReturns);
    const uint16_t* ring = fieldOf<uint16_t>(all, pf::kRing);
    const uint32_t* column = fieldOf<uint32_t>(all, pf::kColumn);
    size_t at = 0, twoReturns = 0;
    double worst = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const std::vector<TraceHit> expected =
          retracedSurfaces(*room.scene, rays, i, o.maxSurfaces, float(o.returnSeparation));
      ASSERT_FALSE(expected.empty()) << i;
      for (size_t j = 0; j < expected.size(); ++j, ++at) {
        ASSERT_LT(at, all.size);
        EXPECT_EQ(ring[at], rays.ring[i]) << i;
        EXPECT_EQ(column[at], rays.column[i]) << i;
        EXPECT_EQ(number[at], j + 1) << i;
        EXPECT_EQ(count[at], expected.size()) << i;
        EXPECT_EQ(range[at], float(double(expected[j].t))) << i << " surface " << j;
        // A ray through an edge meets both its triangles at one t: either may be reported
        // (Filter orders ties by primID, Embree's closest hit need not).
        const TraceHit& h = expected[j];
        const bool onEdge = std::min({h.u, h.v, 1.0f - h.u - h.v}) < 1e-5f;
        if (!onEdge) {
          EXPECT_EQ(primid[at], h.primId) << i << " surface " << j;
        }
      }
      // Analytic: through the pane (x = 1, |y|, |z| < 1, away from its rim), the pane then the
      // wall; elsewhere the wall alone.
      const glm::dvec3 d = rays.direction[i];
      bool edge = false;
      const double wall = wallDistance(d, nullptr, &edge);
      const double py = d.x > 0 ? std::fabs(d.y / d.x) : 2, pz = d.x > 0 ? std::fabs(d.z / d.x) : 2;
      if (edge || std::fabs(py - 1) < 1e-6 || std::fabs(pz - 1) < 1e-6) continue;
      const bool pane = py < 1 && pz < 1;
      ASSERT_EQ(count[at - 1], pane ? 2u : 1u) << i;
      if (pane) {
        ++twoReturns;
        EXPECT_EQ(semantic[at - 2], 6u) << i;
        worst = std::max(worst, std::fabs(range[at - 2] - 1 / d.x) * d.x);
      }
      worst = std::max(worst, std::fabs(range[at - 1] - wall) / wall);
    }
    EXPECT_EQ(at, all.size);
    EXPECT_GT(twoReturns, 100u);
    EXPECT_LE(worst, 1e-5);
  }
}

TEST(Scan, MultiReturnsSkipSurfacesWithinTheSeparationAsRetracingDoes) {
  // 12 panes 1 mm apart (x = 1 .. 1.011) with a separation of 1 cm: the first pane, then the
  // first pane at least 1 cm past it along the ray. Filter collects 2K = 4 primitives a
  // traversal (the first two panes, 2 triangles each): it must traverse again past them.
  for (bool contextFilter : {true, false}) {
    BoxRoom room(12, contextFilter);
    const LidarSensor sensor = roomSensor(90);
    const LidarRays rays = staticRoomRays(sensor);
    ScanOptions o;
    o.returns = ScanReturns::All;
    o.maxSurfaces = 2;
    const PointCloud all = scanSweep(*room.scene, sensor, rays, o).cloud;
    const float* range = fieldOf<float>(all, pf::kRange);
    size_t at = 0, throughPanes = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const std::vector<TraceHit> expected =
          retracedSurfaces(*room.scene, rays, i, o.maxSurfaces, float(o.returnSeparation));
      const glm::dvec3 d = rays.direction[i];
      const bool panes = d.x > 0 && std::fabs(d.y / d.x) < 0.99 && std::fabs(d.z / d.x) < 0.99;
      if (panes) {
        ++throughPanes;
        ASSERT_EQ(expected.size(), 2u) << i;
        // Pane k lies 0.001·k / d.x past the first along the ray: the second surface is the
        // first pane with k >= 10·d.x (rays where that is a near tie are left out).
        const double k = std::ceil(10 * d.x);
        if (k - 10 * d.x > 1e-4) {
          EXPECT_NEAR(double(expected[1].t) * d.x, 1 + 0.001 * k, 1e-5) << i;
        }
      }
      for (size_t j = 0; j < expected.size(); ++j, ++at) {
        ASSERT_LT(at, all.size);
        EXPECT_EQ(range[at], float(double(expected[j].t))) << i << " surface " << j;
      }
    }
    EXPECT_EQ(at, all.size);
    EXPECT_GT(throughPanes, 10u);
  }
}

TEST(Scan, NoiseIsTheSameOnOneAndTwoThreadsAndHasItsSigma) {
  BoxRoom room;
  const LidarSensor sensor = roomSensor(1024 * 1024 / 7 + 1);
  const LidarRays rays = staticRoomRays(sensor);
  ScanOptions o;
  o.noise = {0.02, 0.0, 7};
  LargeBuffer<unsigned char> one, two;
  {
    const ThreadLimit limit(1);
    one = scanSweep(*room.scene, sensor, rays, o).cloud.find(pf::kRange)->bytes;
  }
  {
    const ThreadLimit limit(2);
    two = scanSweep(*room.scene, sensor, rays, o).cloud.find(pf::kRange)->bytes;
  }
  EXPECT_EQ(one, two);
  ASSERT_EQ(one.size(), 4 * rays.size());
  ASSERT_GE(rays.size(), 1000000u);
  double sum = 0, sum2 = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    float r;
    std::memcpy(&r, one.data() + 4 * i, 4);
    const double e = double(r) - wallDistance(rays.direction[i]);
    sum += e, sum2 += e * e;
  }
  const double n = double(rays.size());
  const double sd = std::sqrt(sum2 / n - (sum / n) * (sum / n));
  EXPECT_NEAR(sd, 0.02, 0.05 * 0.02);
}

TEST(Scan, SweepPatterns) {
  EXPECT_EQ(expandSweepPattern("s/{sweep:06d}.ply", 42), "s/000042.ply");
  EXPECT_EQ(expandSweepPattern("s/{sweep}.ply", 42), "s/42.ply");
  EXPECT_EQ(expandSweepPattern("one.las", 3), "one.las");
  EXPECT_NE(test::errorOf([] { expandSweepPattern("{frame}.ply", 0); }).find("{frame}"),
            std::string::npos);
  EXPECT_NE(test::errorOf([] { parseScanFrame("wrld"); }).find("world"), std::string::npos);
  EXPECT_NE(test::errorOf([] { parseScanReturns("strongst"); }).find("strongest"),
            std::string::npos);
}

// Each format's file from a scan that computes only the fields the format writes
// (pointFieldsWrittenAs) is byte for byte the file of a scan that computes every field, for
// every frame and first and all returns (all: point clouds only), with a face property as label.
TEST(Scan, OnlyTheFieldsAFormatWritesGiveTheSameFileAsEveryField) {
  BoxRoom room(2, true);
  const LidarSensor sensor = roomSensor(360);
  auto poseAt = [](int64_t t) {
    Pose p;
    p.translation = glm::dvec3(-0.4 + 0.8 * double(t) / 1e8, 0.2, 0.1);
    return p;
  };
  const LidarRays rays = roomRays(sensor, poseAt);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / cat("aperture_scan_fields_", ::getpid());
  std::filesystem::create_directories(dir);
  const PointWriteOptions writeOptions{"semantic", {"comment"}};
  for (const char* ext : {".ply", ".pcd", ".las", ".bin", ".npz", ".exr"}) {
    const PointFormat format = pointFormatOf(cat("a", ext));
    const bool image = isRangeImageFormat(format);
    for (ScanFrame frame : {ScanFrame::Sensor, ScanFrame::World, ScanFrame::SweepStart})
      for (ScanReturns returns : {ScanReturns::First, ScanReturns::All}) {
        if (image && returns == ScanReturns::All) continue;
        const std::string what = cat(ext, " ", scanFrameName(frame), " ", scanReturnsName(returns));
        ScanOptions o;
        o.frame = frame;
        o.returns = returns;
        o.faceProperties = {"semantic"};
        auto write = [&](const std::string& name, const ScanSweep& sweep) {
          const std::string path = (dir / (name + ext)).string();
          if (image)
            writeRangeImage(path, sweep.image);
          else
            writePointCloud(path, sweep.cloud, writeOptions);
          return path;
        };
        const ScanSweep every = scanSweep(*room.scene, sensor, rays, o, image);
        o.fields = pointFieldsWrittenAs(format, writeOptions);
        const ScanSweep only = scanSweep(*room.scene, sensor, rays, o, image);
        ASSERT_GT(only.points, 0u) << what;
        EXPECT_EQ(only.points, every.points) << what;
        const std::string a = write("every", every), b = write("only", only);
        EXPECT_EQ(test::readFile(a), test::readFile(b)) << what;
        if (format == PointFormat::KittiBin) {
          EXPECT_EQ(test::readFile(kittiLabelPathOf(a)), test::readFile(kittiLabelPathOf(b)))
              << what;
          // x y z intensity instance and the label: nothing else is computed.
          EXPECT_EQ(only.cloud.fields.size(), 6u) << what;
        }
        if (format == PointFormat::Las) {
          EXPECT_LT(only.cloud.fields.size(), every.cloud.fields.size()) << what;
        }
        if (format == PointFormat::Ply) {
          EXPECT_EQ(only.cloud.fields.size(), every.cloud.fields.size()) << what;
        }
      }
  }
  std::filesystem::remove_all(dir);
}

// A scanner that recycles its sweeps (the command's) gives the same subset on every sweep.
TEST(Scan, ARecyclingScannerKeepsItsFieldSubsetSweepAfterSweep) {
  BoxRoom room;
  const LidarSensor sensor = roomSensor(360);
  const LidarRays rays = staticRoomRays(sensor);
  ScanOptions o;
  o.faceProperties = {"semantic"};
  const PointCloud every = scanSweep(*room.scene, sensor, rays, o).cloud;
  o.fields.everyField = false;
  o.fields.names = {pf::kRange, "semantic", pf::kRing};
  SweepScanner scanner(*room.scene, sensor, o);
  for (int k = 0; k < 3; ++k) {
    ScanSweep sweep = scanner.scan(rays);
    ASSERT_EQ(sweep.cloud.fields.size(), 3u);
    for (const PointField& f : sweep.cloud.fields) {
      const PointField* g = every.find(f.name);
      ASSERT_NE(g, nullptr) << f.name;
      EXPECT_EQ(f.type, g->type) << f.name;
      EXPECT_TRUE(f.bytes.size() == g->bytes.size() &&
                  std::memcmp(f.bytes.data(), g->bytes.data(), f.bytes.size()) == 0)
          << f.name << " sweep " << k;
    }
    scanner.recycle(std::move(sweep));
  }
}

}  // namespace
}  // namespace aperture::app
