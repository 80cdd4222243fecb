// glTF cameras on the command line: `batch --mesh scene.glb --cameras scene.glb` renders every
// camera node, named by its node; `render --cameras scene.glb --image NAME` renders the same
// image as the camera given as flags; a size of another aspect is refused before any work.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "core/exr/exr.h"
#include "core/util/units.h"
#include "tests/camera_support.h"
#include "tests/gltf_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// A floor of two triangles and a box-like fan of one primitive, and two perspective camera
/// nodes: "front" (translated) and "above" (translated and turned to look down).
std::string writeCameraScene(const std::string& path) {
  test::GltfScene s;
  test::GltfPrimitive floor;
  floor.positions = {-2, 0, -2, 2, 0, -2, 2, 0, 2, -2, 0, 2};
  floor.indices = {0, 2, 1, 0, 3, 2};
  test::GltfPrimitive wall;
  wall.positions = {-1, 0, -1, 1, 0, -1, 1, 1.5, -1, -1, 0.8, -1};
  wall.indices = {0, 1, 2, 0, 2, 3};
  s.meshes.push_back({"room", {floor, wall}});
  s.cameras.resize(1);
  s.cameras[0].yfov = 0.9;
  s.cameras[0].aspectRatio = 1.5;
  s.nodes.resize(3);
  s.nodes[0].name = "room";
  s.nodes[0].mesh = 0;
  s.nodes[1].name = "front";
  s.nodes[1].camera = 0;
  s.nodes[1].translation = glm::dvec3(0.3, 0.7, 4.0);
  s.nodes[2].name = "above";
  s.nodes[2].camera = 0;
  s.nodes[2].translation = glm::dvec3(0.0, 5.0, 0.5);
  s.nodes[2].rotation = glm::angleAxis(-0.5 * kPi, glm::dvec3(1.0, 0.0, 0.0));
  s.roots = {0, 1, 2};
  return test::writeGltf(s, path);
}

std::string exactText(double x) {
  char s[40];
  std::snprintf(s, sizeof s, "%.17g", x);
  return s;
}

TEST(GltfCamerasCli, BatchRendersEveryCameraNodeAndRenderMatchesFlags) {
  const std::string dir = test::scratchDir();
  const std::string glb = writeCameraScene(dir + "/room.glb");
  std::string log;
  ASSERT_EQ(
      test::runCommand(test::apertureBinary() + " batch --quiet --mesh " + glb + " --cameras " +
                           glb + " --out " + dir + "/out --aov depth --size 60,40",
                       &log),
      0)
      << log;
  const Framebuffer front = readExr(dir + "/out/front.exr");
  const Framebuffer above = readExr(dir + "/out/above.exr");
  EXPECT_EQ(front.width, 60);
  EXPECT_EQ(front.height, 40);

  // "above" looks straight down from y = 5 at the floor (y = 0) and the wall's top (y ≤ 1.5):
  // the centre pixels see depth 5 or less, never more.
  const size_t centre = size_t(20) * 60 + 30;
  EXPECT_LE(above.depth[centre], 5.0f + 1e-5f);
  EXPECT_GE(above.depth[centre], 3.5f - 1e-5f);

  // render with the flags of "front", by hand: eye its translation, looking down −z, y up.
  const std::string flags = " --camera perspective --size 60,40 --fov " +
                            exactText(0.9 * kDegPerRad) + " --clip 0.1," +
                            exactText(double(std::numeric_limits<float>::max())) +
                            " --eye 0.3,0.7,4 --at 0.3,0.7,3 --up 0,1,0";
  ASSERT_EQ(test::runCommand(test::apertureBinary() + " render --quiet --mesh " + glb + flags +
                                 " --aov depth --out " + dir + "/flags.exr",
                             &log),
            0)
      << log;
  ASSERT_EQ(test::runCommand(test::apertureBinary() + " render --quiet --mesh " + glb +
                                 " --cameras " + glb + " --image front --size 60,40" +
                                 " --aov depth --out " + dir + "/file.exr",
                             &log),
            0)
      << log;
  const Framebuffer byFlags = readExr(dir + "/flags.exr"), byFile = readExr(dir + "/file.exr");
  size_t hits = 0;
  for (size_t k = 0; k < byFlags.depth.size(); ++k) {
    hits += std::isfinite(byFlags.depth[k]);
    if (std::isfinite(byFlags.depth[k]))
      EXPECT_NEAR(byFile.depth[k], byFlags.depth[k], 1e-5 * byFlags.depth[k]) << k;
    else
      EXPECT_FALSE(std::isfinite(byFile.depth[k])) << k;
    EXPECT_EQ(front.depth[k], byFile.depth[k]) << k;  // batch and render: the same camera
  }
  EXPECT_GT(hits, byFlags.depth.size() / 10);

  test::expectRefused(test::apertureBinary() + " render --quiet --mesh " + glb + " --cameras " +
                          glb + " --image front --size 60,60 --aov depth --out " + dir +
                          "/square.exr",
                      {"room.glb camera 'front' (/nodes/1)", "aspect ratio 1.5"}, dir);
}

}  // namespace
}  // namespace aperture
