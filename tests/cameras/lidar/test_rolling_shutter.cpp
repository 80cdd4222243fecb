// Rolling-shutter cameras: zero readout is the global-shutter camera bit for bit (rays and a
// rendered frame), and a moving camera's rows move with the trajectory at their own times.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>

#include "cameras/lidar/rolling_shutter.h"
#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/util/error.h"
#include "tests/lidar_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

struct LanesOf16 {
  float ox[16], oy[16], oz[16], tn[16], dx[16], dy[16], dz[16], tm[16], tf[16];
  unsigned mask[16], id[16], flags[16];
  int valid[16];
  RayLanes lanes() { return RayLanes{16, ox, oy, oz, tn, dx, dy, dz, tm, tf, mask, id, flags}; }
};

// Every packet of a W x H camera at the centre ray and two samples, for both cameras.
void forEachPacketPair(const Camera& a, const Camera& b, int width, int height,
                       const std::function<void(const PacketRequest&, LanesOf16&, LanesOf16&)>& f) {
  for (int sample : {PacketRequest::kCentreRay, 0, 1})
    for (int y0 = 0; y0 < height; y0 += 4)
      for (int x0 = 0; x0 < width; x0 += 4) {
        PacketRequest req;
        req.x0 = x0;
        req.y0 = y0;
        req.sample = sample;
        LanesOf16 la{}, lb{};
        RayLanes ra = la.lanes(), rb = lb.lanes();
        a.generate(req, ra, la.valid);
        b.generate(req, rb, lb.valid);
        f(req, la, lb);
      }
}

Trajectory movingTrajectory() {
  TimedPose a, b;
  a.timeNs = 0;
  b.timeNs = 1000000000;
  b.pose.translation = {2.0, 0.0, 0.0};  // 2 m/s along x
  b.pose.rotation = glm::angleAxis(0.3, glm::dvec3(0, 1, 0));
  return Trajectory({a, b}, "moving");
}

TEST(RollingShutter, ZeroReadoutIsTheGlobalShutterCameraBitForBit) {
  const test::BoxRoom room = test::makeBoxRoom({5.0, 4.0, 3.0}, {10.0, 20.0, 1.0});
  for (const char* flags : {"--eye 10,20,1 --at 14,21,0 --size 40x28 --spp 4",
                            "--camera thinlens --eye 11,19,1 --at 10,24,2 --size 36x20 "
                            "--aperture 0.1 --focus 3"}) {
    SCOPED_TRACE(flags);
    const CameraParams p = test::cameraParamsFromFlags(flags);
    std::shared_ptr<const Camera> base = makeCamera(p, room.scene->renderOrigin());
    const auto rolling = rollingShutterCamera(base, movingTrajectory(), 250000000, 0.0, p.height,
                                              room.scene->renderOrigin());
    forEachPacketPair(*base, *rolling, p.width, p.height,
                      [](const PacketRequest&, LanesOf16& a, LanesOf16& b) {
                        EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0);
                      });
    RenderSettings settings;
    settings.spp = p.spp;
    Framebuffer fa(p.width, p.height, parseAovList("all")),
        fb(p.width, p.height, parseAovList("all"));
    renderImage(*room.scene, *base, settings, fa);
    renderImage(*room.scene, *rolling, settings, fb);
    test::expectIdentical(fa, fb, "zero readout against global shutter");
  }
}

TEST(RollingShutter, RowsMoveWithTheTrajectoryAtTheirOwnTimes) {
  const glm::dvec3 renderOrigin(10.0, 20.0, 1.0);
  const CameraParams p = test::cameraParamsFromFlags("--eye 10,20,1 --at 10,20,-5 --size 16x12");
  std::shared_ptr<const Camera> base = makeCamera(p, renderOrigin);
  const double readout = 0.01;  // 10 ms per row
  const Trajectory trajectory = movingTrajectory();
  const auto rolling =
      rollingShutterCamera(base, trajectory, 100000000, readout, p.height, renderOrigin);
  const Pose start = trajectory.at(100000000);
  double worst = 0;
  forEachPacketPair(
      *base, *rolling, p.width, p.height,
      [&](const PacketRequest& req, LanesOf16& a, LanesOf16& b) {
        for (int k = 0; k < 16; ++k) {
          if (!a.valid[k]) continue;
          const int row = req.pixel(k).row;
          // The row's motion since the frame's start, applied to the base ray in world space.
          const Pose motion = trajectory.at(100000000 + int64_t(row) * 10000000) * start.inverse();
          const glm::dvec3 o =
              motion.apply(glm::dvec3(a.ox[k], a.oy[k], a.oz[k]) + renderOrigin) - renderOrigin;
          const glm::dvec3 d = motion.applyDirection(glm::dvec3(a.dx[k], a.dy[k], a.dz[k]));
          worst = std::max(worst, glm::length(o - glm::dvec3(b.ox[k], b.oy[k], b.oz[k])));
          worst = std::max(worst, glm::length(d - glm::dvec3(b.dx[k], b.dy[k], b.dz[k])));
          if (row == 0) {
            EXPECT_EQ(std::memcmp(&a.ox[k], &b.ox[k], sizeof(float)), 0);
          }
        }
      });
  EXPECT_LT(worst, 1e-5);
  // The last row was read 110 ms later: its eye is the frame start's eye moved by the
  // trajectory's motion over those 110 ms.
  glm::dvec3 o, d;
  ASSERT_TRUE(rolling->centreRayAt(8.0, 11.5, o, d));
  const Pose motion = trajectory.at(210000000) * start.inverse();
  EXPECT_LT(glm::length(o - (motion.apply(renderOrigin) - renderOrigin)), 1e-9);
  EXPECT_GT(glm::length(o), 0.2);
  EXPECT_FALSE(rolling->sharedRayOrigin().has_value());

  EXPECT_THROW(rollingShutterCamera(base, trajectory, 990000000, readout, p.height, renderOrigin),
               Error);
  EXPECT_THROW(rollingShutterCamera(base, trajectory, 0, -1.0, p.height, renderOrigin), Error);
}

}  // namespace
}  // namespace aperture
