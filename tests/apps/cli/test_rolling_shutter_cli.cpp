// `aperture render --rolling-shutter`: zero readout is the global-shutter image bit for bit, a
// moving camera's image differs, and bad flags fail before any output.
#include <gtest/gtest.h>

#include "core/exr/exr.h"
#include "tests/support.h"

namespace aperture {
namespace {

const char* const kShutterSphere = "'procedural:sphere?segments=64&rings=32'";

std::string renderShutter(const std::string& dir, const std::string& name, const std::string& extra,
                          int* code = nullptr, std::string* output = nullptr) {
  const std::string out = dir + "/" + name + ".exr";
  const int c =
      test::runCommand(test::apertureBinary() + " render --quiet --mesh " + kShutterSphere +
                           " --eye 0.3,0.2,3 --at 0,0,0 --size 48x36 --aov depth,normal "
                           "--out " +
                           out + " " + extra,
                       output);
  if (code) *code = c;
  return out;
}

TEST(RollingShutterCli, ZeroReadoutIsTheGlobalShutterImageAndMotionIsNot) {
  const std::string dir = test::scratchDir();
  test::writeFile(dir + "/poses.txt",
                  "100 0 0 0 0 0 0 1\n"
                  "101 1.5 0 0 0 0.0998334 0 0.9950042\n");
  int code = 0;
  const std::string global = renderShutter(dir, "global", "", &code);
  ASSERT_EQ(code, 0);
  const std::string zero =
      renderShutter(dir, "zero", "--rolling-shutter 0 --trajectory " + dir + "/poses.txt", &code);
  ASSERT_EQ(code, 0);
  const std::string moving = renderShutter(
      dir, "moving", "--rolling-shutter 0.005 --time 100.2 --trajectory " + dir + "/poses.txt",
      &code);
  ASSERT_EQ(code, 0);
  const Framebuffer g = readExr(global), z = readExr(zero), m = readExr(moving);
  EXPECT_EQ(test::differingAovs(g, z), "");
  EXPECT_NE(test::differingAovs(g, m), "");

  std::string output;
  const std::string noTrajectory =
      renderShutter(dir, "none", "--rolling-shutter 0.001", &code, &output);
  EXPECT_EQ(code, 1);
  EXPECT_NE(output.find("--trajectory"), std::string::npos) << output;
  EXPECT_FALSE(test::fileExists(noTrajectory));
  // 36 rows 0.05 s apart from t = 100.5 end after the trajectory's last time, 101.
  const std::string outside = renderShutter(
      dir, "outside", "--rolling-shutter 0.05 --time 100.5 --trajectory " + dir + "/poses.txt",
      &code, &output);
  EXPECT_EQ(code, 1);
  EXPECT_NE(output.find("outside the trajectory"), std::string::npos) << output;
  EXPECT_FALSE(test::fileExists(outside));
}

}  // namespace
}  // namespace aperture
