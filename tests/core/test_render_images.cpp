// renderImages (several frames in one parallel loop over (camera, tile)) against renderImage
// of each frame alone: the independent path is the one-frame loop every other test checks.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "cameras/registry.h"
#include "core/error.h"
#include "core/mesh.h"
#include "core/render.h"
#include "core/scene.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// A sphere in front of a quad: two objects, so geomID varies across the image.
struct TwoObjects {
  Device device;
  Mesh sphere = makeProcedural("procedural:sphere");
  Mesh plane = makeProcedural("procedural:quad?size=8&z=-1.5");
  std::unique_ptr<Scene> scene;
  TwoObjects() {
    LoadOptions o;
    o.placement = Placement::WorldSpace;
    finishMesh(sphere, o);
    finishMesh(plane, o);
    scene = std::make_unique<Scene>(device, std::vector<const Mesh*>{&sphere, &plane});
  }
};

CameraParams cameraOf(const char* type, int width, int height, int spp) {
  CameraParams p;
  p.type = type;
  p.width = width;
  p.height = height;
  p.spp = spp;
  p.eye = {0.3, 1.5, 4.0};
  p.at = glm::dvec3(0.0, 0.0, 0.0);
  if (p.type == "orthographic") p.viewport = glm::dvec2(4.0, 3.0);
  return p;
}

const AovSet kEveryFixedAov = parseAovSet("all");

}  // namespace

TEST(RenderImages, EachFrameEqualsRenderImageForMixedSizesAndTypes) {
  TwoObjects s;
  // Sizes that are not multiples of the tile or block size, one frame smaller than a tile,
  // several camera models and spp (colour averages samples; geometry from the centre ray).
  const std::vector<CameraParams> params = {
      cameraOf("perspective", 97, 61, 1), cameraOf("orthographic", 33, 70, 1),
      cameraOf("thinlens", 40, 40, 4),    cameraOf("equirect", 128, 64, 1),
      cameraOf("fisheye", 17, 5, 2),      cameraOf("perspective", 1, 1, 1),
  };
  std::vector<std::unique_ptr<Camera>> owned;
  std::vector<const Camera*> cameras;
  std::vector<Framebuffer> batch;
  for (const CameraParams& p : params) {
    owned.push_back(makeCamera(p, s.scene->renderOrigin()));
    cameras.push_back(owned.back().get());
    batch.emplace_back(p.width, p.height, kEveryFixedAov);
  }
  RenderSettings settings;
  settings.tileSize = 16;
  const std::vector<RenderStats> stats = renderImages(*s.scene, cameras, settings, batch);
  ASSERT_EQ(stats.size(), params.size());
  uint64_t anyHits = 0;
  for (size_t k = 0; k < params.size(); ++k) {
    Framebuffer alone(params[k].width, params[k].height, kEveryFixedAov);
    RenderSettings one = settings;
    one.spp = params[k].spp;
    const RenderStats single = renderImage(*s.scene, *cameras[k], one, alone);
    EXPECT_EQ(test::differingAovs(batch[k], alone), "") << "frame " << k << " " << params[k].type;
    EXPECT_EQ(stats[k].raysTraced, single.raysTraced) << "frame " << k;
    EXPECT_EQ(stats[k].hits, single.hits) << "frame " << k;
    EXPECT_EQ(stats[k].raysSkipped, single.raysSkipped) << "frame " << k;
    anyHits += single.hits;
  }
  EXPECT_GT(anyHits, 1000u) << "the cameras should see the scene";
}

TEST(RenderImages, ProgressCountsEveryFrameOnceInOrder) {
  TwoObjects s;
  std::vector<std::unique_ptr<Camera>> owned;
  std::vector<const Camera*> cameras;
  std::vector<Framebuffer> fbs;
  for (int k = 0; k < 7; ++k) {
    owned.push_back(makeCamera(cameraOf("perspective", 20 + 9 * k, 30, 1)));
    cameras.push_back(owned.back().get());
    fbs.emplace_back(20 + 9 * k, 30, AovSet(kAovDepth));
  }
  std::vector<size_t> calls;
  renderImages(*s.scene, cameras, RenderSettings{}, fbs,
               [&](size_t done) { calls.push_back(done); });
  const std::vector<size_t> expected = {1, 2, 3, 4, 5, 6, 7};
  EXPECT_EQ(calls, expected);
}

TEST(RenderImages, RefusesMismatchedFramebuffers) {
  TwoObjects s;
  const auto camera = makeCamera(cameraOf("perspective", 32, 32, 1));
  std::vector<const Camera*> cameras = {camera.get(), camera.get()};
  std::vector<Framebuffer> one = {Framebuffer(32, 32, AovSet(kAovDepth))};
  EXPECT_THROW(renderImages(*s.scene, cameras, RenderSettings{}, one), Error);
  std::vector<Framebuffer> wrongSize = {Framebuffer(32, 32, AovSet(kAovDepth)),
                                        Framebuffer(31, 32, AovSet(kAovDepth))};
  EXPECT_THROW(renderImages(*s.scene, cameras, RenderSettings{}, wrongSize), Error);
}
