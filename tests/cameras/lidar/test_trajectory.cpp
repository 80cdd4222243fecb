// Trajectories: TUM and KITTI rows, interpolation (linear position, slerp rotation), exact
// nanosecond times, and the errors of non-increasing times and times outside.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/quaternion.hpp>

#include "cameras/lidar/trajectory.h"
#include "core/util/error.h"
#include "tests/lidar_support.h"

namespace aperture {
namespace {

std::string writeTrajectory(const std::string& name, const std::string& text) {
  return test::writeScratchFile(name, text);
}

template <class F>
std::string trajectoryError(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Trajectory, TimesAreExactNanoseconds) {
  EXPECT_EQ(parseTimeNs("1305031102.175304", "t"), 1305031102175304000LL);
  EXPECT_EQ(parseTimeNs("-2.5", "t"), -2500000000LL);
  EXPECT_EQ(parseTimeNs("7", "t"), 7000000000LL);
  EXPECT_EQ(parseTimeNs("0.0000000015", "t"), 2);  // past nine decimals: nearest ns
  EXPECT_EQ(parseTimeNs("1e-3", "t"), 1000000);
  EXPECT_EQ(formatTimeNs(1305031102175304000LL), "1305031102.175304000");
  EXPECT_EQ(formatTimeNs(-1), "-0.000000001");
  EXPECT_NE(
      trajectoryError([] { parseTimeNs("abc", "poses.txt line 3"); }).find("poses.txt line 3"),
      std::string::npos);
}

TEST(Trajectory, TumRowsInterpolateLinearlyAndBySlerp) {
  // From the identity at t = 10 to 90° about z and (2, 4, 6) at t = 12.
  const double h = std::sqrt(0.5);
  const std::string path = writeTrajectory("tum.txt",
                                           "# timestamp tx ty tz qx qy qz qw\n"
                                           "10 0 0 0 0 0 0 1\n\n"
                                           "12.0 2 4 6 0 0 " +
                                               std::to_string(h) + " " + std::to_string(h) + "\n");
  const Trajectory t = loadTrajectory(path);
  EXPECT_EQ(t.startNs(), 10000000000LL);
  EXPECT_EQ(t.endNs(), 12000000000LL);
  EXPECT_FALSE(t.isStatic());
  const Pose mid = t.at(11000000000LL);
  EXPECT_LT(glm::length(mid.translation - glm::dvec3(1, 2, 3)), 1e-12);
  // Halfway: 45° about z.
  const glm::dvec3 x = mid.applyDirection({1, 0, 0});
  EXPECT_NEAR(x.x, std::cos(M_PI / 4), 1e-6);
  EXPECT_NEAR(x.y, std::sin(M_PI / 4), 1e-6);
  EXPECT_NEAR(x.z, 0, 1e-12);
  // A quarter of the way: 22.5° and a quarter of the translation.
  const Pose quarter = t.at(10500000000LL);
  const glm::dvec3 xq = quarter.applyDirection({1, 0, 0});
  EXPECT_NEAR(std::atan2(xq.y, xq.x), M_PI / 8, 1e-6);
  EXPECT_LT(glm::length(quarter.translation - glm::dvec3(0.5, 1, 1.5)), 1e-12);
  // The rows' own poses exactly.
  EXPECT_EQ(t.at(10000000000LL).translation, glm::dvec3(0.0));
  EXPECT_EQ(t.at(12000000000LL).translation, glm::dvec3(2, 4, 6));

  const std::string e = trajectoryError([&] { t.at(12000000001LL); });
  EXPECT_NE(e.find("12.000000001"), std::string::npos) << e;
  EXPECT_NE(e.find(path), std::string::npos) << e;
}

TEST(Trajectory, OnePoseIsAStaticSensor) {
  const std::string path = writeTrajectory("one.txt", "5 1 2 3 0 0 0 1\n");
  const Trajectory t = loadTrajectory(path);
  EXPECT_TRUE(t.isStatic());
  EXPECT_EQ(t.at(-100).translation, glm::dvec3(1, 2, 3));
  EXPECT_EQ(t.at(int64_t(1) << 60).translation, glm::dvec3(1, 2, 3));
}

TEST(Trajectory, KittiRowsTakeTheirTimesFromTheTimesFile) {
  const std::string poses = writeTrajectory("poses.txt",
                                            "1 0 0 0 0 1 0 0 0 0 1 0\n"
                                            "0 -1 0 10 1 0 0 0 0 0 1 0\n");
  const std::string times = writeTrajectory("times.txt", "0.000000e+00\n1.000000e-01\n");
  const Trajectory t = loadTrajectory(poses, times);
  EXPECT_EQ(t.endNs(), 100000000);
  const Pose last = t.at(100000000);
  EXPECT_LT(glm::length(last.apply({1, 0, 0}) - glm::dvec3(10, 1, 0)), 1e-12);
  const Pose mid = t.at(50000000);
  EXPECT_LT(glm::length(mid.translation - glm::dvec3(5, 0, 0)), 1e-12);

  EXPECT_NE(trajectoryError([&] { loadTrajectory(poses); }).find("times file"), std::string::npos);
  const std::string fewTimes = writeTrajectory("few.txt", "0\n");
  EXPECT_NE(trajectoryError([&] { loadKittiTrajectory(poses, fewTimes); }).find("1 times"),
            std::string::npos);
}

TEST(Trajectory, NonIncreasingTimesNameTheLine) {
  const std::string path = writeTrajectory("back.txt",
                                           "1 0 0 0 0 0 0 1\n"
                                           "2 0 0 0 0 0 0 1\n"
                                           "2 1 0 0 0 0 0 1\n");
  const std::string e = trajectoryError([&] { loadTrajectory(path); });
  EXPECT_NE(e.find(path + " line 3"), std::string::npos) << e;
  EXPECT_NE(e.find("must increase"), std::string::npos) << e;

  const std::string bad = writeTrajectory("bad.txt", "1 0 0 0 0 0 0\n");
  EXPECT_NE(trajectoryError([&] { loadTrajectory(bad); }).find("line 1"), std::string::npos);
  const std::string badQ = writeTrajectory("badq.txt", "1 0 0 0 0 0 0 2\n");
  EXPECT_NE(trajectoryError([&] { loadTrajectory(badQ); }).find("line 1"), std::string::npos);
}

}  // namespace
}  // namespace aperture
