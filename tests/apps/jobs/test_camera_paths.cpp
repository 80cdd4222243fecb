// Camera paths in job files (apps/jobs/camera_paths.h): orbit eyes against hand-computed
// positions, keyframes interpolated linearly and held at the ends, and keyframes that must ascend.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/jobs/job.h"
#include "tests/job_support.h"

using namespace aperture;
using aperture::app::Job;
using aperture::test::baseJob;
using aperture::test::jobParseError;
using aperture::test::parseJobJson;
using nlohmann::json;

TEST(JobPaths, OrbitEyesMatchHandComputedPositions) {
  json j = baseJob();
  // Up +Y: frame k sits at azimuth start + sweep * k / frames, measured from +Z towards +X.
  j["cameras"][0] = {
      {"name", "o"},
      {"orbit", {{"centre", {1, 2, 3}}, {"radius", 4}, {"height", 0.5}, {"start", 90}}},
      {"frames", 4}};
  // Elevation 30 degrees at distance 2, up +Z: the reference direction becomes +X.
  j["cameras"].push_back({{"name", "e"},
                          {"orbit", {{"radius", 2}, {"elevation", 30}, {"sweep", 180}}},
                          {"frames", 2},
                          {"up", {0, 0, 1}}});
  const Job job = parseJobJson(j);
  ASSERT_EQ(job.images.size(), 6u);
  auto expectEye = [&](size_t index, glm::dvec3 expected) {
    const glm::dvec3 eye = job.images[index].params.eye;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(eye[c], expected[c], 1e-12) << index << " axis " << c;
  };
  expectEye(0, {5, 2.5, 3});             // 90 degrees: +X
  expectEye(1, {1, 2.5, -1});            // 180 degrees: -Z
  expectEye(2, {-3, 2.5, 3});            // 270 degrees: -X
  expectEye(3, {1, 2.5, 7});             // 360 degrees: +Z
  expectEye(4, {std::sqrt(3.0), 0, 1});  // azimuth 0 along +X, raised 30 degrees along +Z
  expectEye(5, {0, std::sqrt(3.0), 1});  // azimuth 90: +Y (= up x X)
  EXPECT_EQ(job.images[1].params.at.value(), glm::dvec3(1, 2, 3));
  EXPECT_EQ(job.images[1].camera, "o");
  EXPECT_EQ(job.images[1].frame, 1);
  EXPECT_EQ(job.images[4].index, 4u);
}

TEST(JobPaths, KeyframesInterpolateLinearlyAndHoldAtTheEnds) {
  json j = baseJob();
  j["cameras"][0] = {
      {"name", "k"},
      {"frames", 7},
      {"keyframes",
       {{{"frame", 1}, {"eye", {0, 0, 10}}, {"at", {0, 0, 0}}, {"fov", 40}},
        {{"frame", 5}, {"eye", {8, 4, 10}}, {"at", {0, 2, 0}}, {"up", {0, 1, 0.4}}, {"fov", 60}}}}};
  const Job job = parseJobJson(j);
  ASSERT_EQ(job.images.size(), 7u);
  auto near = [](glm::dvec3 a, glm::dvec3 b) { return glm::length(a - b) < 1e-12; };
  const CameraParams& f0 = job.images[0].params;  // before the first keyframe: held
  EXPECT_TRUE(near(f0.eye, {0, 0, 10}));
  EXPECT_DOUBLE_EQ(*f0.fovDeg, 40);
  const CameraParams& f2 = job.images[2].params;  // t = 1/4
  EXPECT_TRUE(near(f2.eye, {2, 1, 10}));
  EXPECT_TRUE(near(*f2.at, {0, 0.5, 0}));
  EXPECT_TRUE(near(f2.up, {0, 1, 0.1}));
  EXPECT_NEAR(*f2.fovDeg, 45, 1e-12);
  const CameraParams& f4 = job.images[4].params;  // t = 3/4
  EXPECT_TRUE(near(f4.eye, {6, 3, 10}));
  EXPECT_NEAR(*f4.fovDeg, 55, 1e-12);
  const CameraParams& f6 = job.images[6].params;  // after the last keyframe: held
  EXPECT_TRUE(near(f6.eye, {8, 4, 10}));
  EXPECT_NEAR(*f6.fovDeg, 60, 1e-12);
  // Keyframes must ascend.
  j["cameras"][0]["keyframes"][1]["frame"] = 1;
  EXPECT_NE(jobParseError(j).find("cameras[0].keyframes[1].frame: 1: keyframes must ascend"),
            std::string::npos);
}
