// The bench's bare-Embree baseline (bench/measure/baseline.h) traces the camera's rays: its minimal
// float pinhole generation must give the frame loop's rays up to float rounding, pixel for
// pixel (a half-pixel or axis slip would move them by far more), and count the same rays.
#include <gtest/gtest.h>

#include <cmath>

#include "bench/measure/baseline.h"
#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/aov/framebuffer.h"
#include "core/engine/packet.h"
#include "core/engine/render.h"
#include "core/mesh/mesh.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// Largest difference between the baseline's pinhole rays and the camera's centre rays over
/// every 4x4 block of the image (directions; origins must be equal).
double largestDirectionGap(const std::string& flags, int width, int height) {
  const CameraParams params = test::cameraParamsFromFlags(flags);
  const auto camera = makeCameraModel(params, glm::dvec3(0.25, -0.5, 0.75));
  const BaselineTracer base(*camera, width, height, 32);
  EXPECT_EQ(base.rayGeneration(), "float pinhole in the loop") << flags;
  EXPECT_EQ(base.rayCount(), uint64_t(width) * uint64_t(height));
  double gap = 0;
  alignas(64) RTCRayHit16 mine;
  alignas(64) RTCRay16 bare;
  alignas(64) int validMine[16], validBare[16];
  RayLanes lanes = rayLanes<16>(mine);
  for (int y0 = 0; y0 < height; y0 += 4)
    for (int x0 = 0; x0 < width; x0 += 4) {
      const PacketRequest req{x0, y0, 4, 4, PacketRequest::kCentreRay};
      camera->generate(req, lanes, validMine);
      base.pinholeRays(x0, y0, bare, validBare);
      for (int k = 0; k < 16; ++k) {
        EXPECT_EQ(validBare[k] != 0, req.inImage(k, width, height));
        if (!req.inImage(k, width, height)) continue;
        EXPECT_EQ(bare.org_x[k], mine.ray.org_x[k]);
        EXPECT_EQ(bare.org_z[k], mine.ray.org_z[k]);
        gap = std::max({gap, double(std::fabs(bare.dir_x[k] - mine.ray.dir_x[k])),
                        double(std::fabs(bare.dir_y[k] - mine.ray.dir_y[k])),
                        double(std::fabs(bare.dir_z[k] - mine.ray.dir_z[k]))});
      }
    }
  return gap;
}

TEST(Baseline, PinholeRaysAreTheCamerasRays) {
  // 61x45: blocks cut by the right and bottom edges. A shift and an oblique up vector check
  // the window centre and the frame; 1e-5 is far below a pixel's angle here (~1e-2).
  const char* cases[] = {"--eye 0.3,3,12 --at 0,0.5,0 --fov 40 --size 61,45",
                         "--eye 0.3,3,12 --at 0,0.5,0 --fov 40 --shift 0.1,-0.2 --size 61,45",
                         "--eye 1,2,3 --dir -0.2,-0.1,-1 --up 0.3,1,0 --fov 70 --size 61,45"};
  for (const char* flags : cases) EXPECT_LT(largestDirectionGap(flags, 61, 45), 1e-5) << flags;
}

TEST(Baseline, OtherCamerasUsePreGeneratedRays) {
  for (const char* flags :
       {"--camera thinlens --eye 0,0,5 --aperture 0.1 --focus 5 --size 8,8",
        "--eye 0,0,5 --fov 40 --clip 1,9 --size 8,8", "--camera fisheye --eye 0,0,5 --size 8,8"}) {
    const auto camera = makeCameraModel(test::cameraParamsFromFlags(flags), glm::dvec3(0.0));
    EXPECT_EQ(BaselineTracer(*camera, 8, 8, 4).rayGeneration(), "pre-generated") << flags;
  }
}

}  // namespace

namespace {

TEST(Baseline, EveryEmbreeApiHitsWhatTheFrameLoopHits) {
  // The streams (one call per tile) must trace exactly the packet path's rays: the hit count
  // of each equals the frame loop's on a sphere that covers part of the image, for the
  // in-loop pinhole and for pre-generated rays (a shifted thin lens at spp 1).
  Device device;
  Mesh sphere = makeProcedural("procedural:sphere");
  LoadOptions world;
  world.placement = Placement::WorldSpace;
  finishMesh(sphere, world);
  Scene scene(device, {&sphere});
  for (const char* flags :
       {"--eye 0.3,0.4,3 --at 0,0,0 --fov 45 --size 61,45",
        "--camera thinlens --eye 0.3,0.4,3 --at 0,0,0 --fov 45 --aperture 0.05 --focus 3 "
        "--size 61,45"}) {
    const auto camera = makeCameraModel(test::cameraParamsFromFlags(flags), glm::dvec3(0.0));
    Framebuffer fb(61, 45, parseAovList("depth"));
    const RenderStats frameLoop = renderImage(scene, *camera, RenderSettings{}, fb);
    ASSERT_GT(frameLoop.hits, 100u);
    ASSERT_LT(frameLoop.hits, uint64_t(61 * 45));
    for (BaselineApi api : {BaselineApi::Packet16, BaselineApi::StreamNM, BaselineApi::Stream1M})
      EXPECT_EQ(BaselineTracer(*camera, 61, 45, 16, api).countHits(scene), frameLoop.hits)
          << flags << " " << baselineApiName(api);
  }
}

}  // namespace
