// Job files: a camera's "blender" block (bpy.types.Camera's property names) reaches the camera
// as the schema parameters it names, and its mistakes are refused with the JSON path.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/jobs/job.h"
#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/util/error.h"

namespace aperture {
namespace {

using nlohmann::json;

json blenderJob(const json& block) {
  json j = json::parse(R"({
    "scene": {"meshes": [{"path": "procedural:sphere"}]},
    "cameras": [{"name": "cam", "eye": [0, 0, 5], "at": [0, 0, 0]}],
    "size": [480, 640],
    "output": "out/{camera}.exr"
  })");
  j["cameras"][0]["blender"] = block;
  return j;
}

CameraParams parsedParams(const json& j) {
  const app::Job job = app::parseJobText(j.dump(), "job.json", "");
  EXPECT_EQ(job.images.size(), 1u);
  return job.images.at(0).params;
}

std::string parseError(const json& j) {
  try {
    app::parseJobText(j.dump(), "job.json", "");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(JobBlender, EveryValueReachesTheCamera) {
  const CameraParams p = parsedParams(blenderJob({{"lens", 35},
                                                  {"sensor_width", 32},
                                                  {"sensor_height", 18},
                                                  {"sensor_fit", "HORIZONTAL"},
                                                  {"shift_x", 0.1},
                                                  {"shift_y", -0.05},
                                                  {"clip_start", 0.5},
                                                  {"clip_end", 40}}));
  ASSERT_TRUE(p.focalLengthMm && p.blenderShift && p.clip);
  EXPECT_EQ(*p.focalLengthMm, 35.0);
  EXPECT_EQ(p.sensorMm, glm::dvec2(32, 18));
  EXPECT_EQ(p.sensorFit, SensorFit::Horizontal);
  EXPECT_EQ(*p.blenderShift, glm::dvec2(0.1, -0.05));
  EXPECT_EQ(*p.clip, glm::dvec2(0.5, 40));
  // The camera: HORIZONTAL on a 480 x 640 image spans the width with 32 mm; the shift is in
  // widths (Blender's view plane moves by shift·480 px on both axes).
  const auto cam = makeCameraModel(p);
  EXPECT_NEAR(cam->vw(), 32.0 / 35.0, 1e-15);
  EXPECT_NEAR(cam->vh(), 32.0 / 35.0 * 640.0 / 480.0, 1e-15);
  EXPECT_NEAR(cam->shift().x, 0.1 * 480.0 / 480.0, 1e-15);
  EXPECT_NEAR(cam->shift().y, -0.05 * 480.0 / 640.0, 1e-15);
}

TEST(JobBlender, KeysLeftOutKeepBlendersDefaults) {
  const CameraParams p = parsedParams(blenderJob(json::object()));
  ASSERT_TRUE(p.focalLengthMm);
  EXPECT_EQ(*p.focalLengthMm, 50.0);  // Blender's default lens
  EXPECT_EQ(p.sensorMm, glm::dvec2(36, 24));
  EXPECT_EQ(p.sensorFit, SensorFit::Auto);
  EXPECT_FALSE(p.blenderShift);
  EXPECT_FALSE(p.clip);
  // One clip key: the other is Blender's default (clip_start 0.1, clip_end 1000).
  EXPECT_EQ(parsedParams(blenderJob({{"clip_end", 30}})).clip, glm::dvec2(0.1, 30));
  EXPECT_EQ(parsedParams(blenderJob({{"clip_start", 2}})).clip, glm::dvec2(2, 1000));
}

// bpy's Camera.angle is 2·atan(s / (2·lens)) with s the fitted sensor side (the height for
// VERTICAL): the block's angle gives back that lens.
TEST(JobBlender, AngleIsTheFieldOfViewAcrossTheFittedSensorSide) {
  const double lens = 42.0;
  const double angleW = 2.0 * std::atan(36.0 / (2.0 * lens));
  const double angleH = 2.0 * std::atan(24.0 / (2.0 * lens));
  EXPECT_NEAR(*parsedParams(blenderJob({{"angle", angleW}})).focalLengthMm, lens, 1e-12);
  EXPECT_NEAR(
      *parsedParams(blenderJob({{"angle", angleH}, {"sensor_fit", "VERTICAL"}})).focalLengthMm,
      lens, 1e-12);
  EXPECT_NE(parseError(blenderJob({{"angle", 0.5}, {"lens", 50}})).find("lens or angle"),
            std::string::npos);
  EXPECT_NE(parseError(blenderJob({{"angle", 4.0}})).find("cameras[0].blender.angle"),
            std::string::npos);
}

TEST(JobBlender, MistakesAreRefusedWithTheJsonPath) {
  std::string msg = parseError(blenderJob({{"lens", 35}, {"sensor_widht", 36}}));
  EXPECT_NE(msg.find("job.json: cameras[0].blender.sensor_widht"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean 'sensor_width'?"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("job.json: job.json"), std::string::npos) << msg;

  msg = parseError(blenderJob({{"sensor_fit", "HORIZONTL"}}));
  EXPECT_NE(msg.find("cameras[0].blender.sensor_fit"), std::string::npos) << msg;
  EXPECT_NE(msg.find("did you mean 'HORIZONTAL'?"), std::string::npos) << msg;

  msg = parseError(blenderJob({{"lens", 0}}));
  EXPECT_NE(msg.find("cameras[0].blender.lens"), std::string::npos) << msg;

  msg = parseError(blenderJob({{"lens", "50"}}));
  EXPECT_NE(msg.find("cameras[0].blender.lens: expected a number"), std::string::npos) << msg;

  msg = parseError(blenderJob({{"clip_start", 5}, {"clip_end", 1}}));
  EXPECT_NE(msg.find("clip"), std::string::npos) << msg;

  // The same parameter given twice, in the block and as the entry's own key.
  json j = blenderJob({{"lens", 35}});
  j["cameras"][0]["focal_length"] = 50;
  msg = parseError(j);
  EXPECT_NE(msg.find("cameras[0].blender.lens"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cameras[0].focal_length"), std::string::npos) << msg;

  // Blender's lens and a fov: the schema's conflict, naming both.
  j = blenderJob({{"lens", 35}});
  j["cameras"][0]["fov"] = 40;
  msg = parseError(j);
  EXPECT_NE(msg.find("conflict"), std::string::npos) << msg;

  // A Blender block on a model that has no lens.
  j = blenderJob({{"lens", 35}});
  j["cameras"][0]["type"] = "fisheye";
  msg = parseError(j);
  EXPECT_NE(msg.find("cameras[0].blender.lens: does not apply to a 'fisheye'"), std::string::npos)
      << msg;
}

}  // namespace
}  // namespace aperture
