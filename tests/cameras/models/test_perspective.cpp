// Camera tests that need the frame loop: a shifted camera renders the crop of a larger
// unshifted one, pixel for pixel on Z and primID.
#include <gtest/gtest.h>

#include "cameras/registry/registry.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"

namespace aperture {
namespace {

TEST(PerspectiveShift, ImageEqualsTheCropOfALargerViewportOnZAndPrimId) {
  const Mesh city = loadMesh("procedural:city");
  Device device;
  Scene scene(device, {&city});
  // Powers of two keep both pixel mappings exact, so the rays are bit-identical.
  CameraParams a;
  a.eye = {1.0, 7.0, 19.0};
  a.at = glm::dvec3(0.0, 1.5, 0.0);
  a.width = 128;
  a.height = 64;
  a.d = 1.0;
  a.viewport = glm::dvec2(2.0, 1.0);
  a.shift = {0.25, -0.125};
  CameraParams b = a;
  b.width = 256;
  b.height = 128;
  b.viewport = glm::dvec2(4.0, 2.0);
  b.shift = {0.0, 0.0};
  const int dj = 96, di = 40;  // W·(½ + sx), H·(½ − sy)
  const auto camA = makeCamera(a, scene.renderOrigin());
  const auto camB = makeCamera(b, scene.renderOrigin());
  for (int width : {16, 4}) {
    RenderSettings settings;
    settings.packetWidth = width;
    Framebuffer fa(a.width, a.height, kAovDepth | kAovPrimId);
    Framebuffer fb(b.width, b.height, kAovDepth | kAovPrimId);
    renderImage(scene, *camA, settings, fa);
    settings.packetWidth = 16;
    renderImage(scene, *camB, settings, fb);
    size_t hits = 0;
    for (int i = 0; i < a.height; ++i)
      for (int j = 0; j < a.width; ++j) {
        const size_t ka = size_t(i) * a.width + j, kb = size_t(i + di) * b.width + (j + dj);
        ASSERT_EQ(fa.primId[ka], fb.primId[kb]) << "pixel " << i << "," << j;
        ASSERT_EQ(fa.depth[ka], fb.depth[kb]) << "pixel " << i << "," << j;
        hits += fa.primId[ka] != kInvalidId;
      }
    EXPECT_GT(hits, fa.pixelCount() / 4) << "the shifted window must see the city";
  }
}

}  // namespace
}  // namespace aperture
