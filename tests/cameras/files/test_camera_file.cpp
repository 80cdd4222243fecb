// Camera files (cameras/files/camera_file.cpp): the pixel-centre and axis conventions shown to
// catch a half-pixel slip and an axis flip, and the sidecar JSON. The formats are tested in
// test_colmap_file.cpp, test_nerf_file.cpp and test_opencv_file.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>

#include "cameras/files/camera_file.h"
#include "cameras/lenses/calibration.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "tests/camera_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::errorOf;

namespace fs = std::filesystem;
using nlohmann::json;
using test::apply;
using test::expectSameFile;
using test::expectSamePoses;
using test::rc;
using test::readFile;
using test::scratchDir;
using test::writeFile;

// ---- conventions ----

TEST(CameraFileConventions, PixelCentres) {
  // Pixel (row 2, column 3): raster centre (3.5, 2.5); OpenCV calls it (3, 2).
  const glm::dvec2 raster(3.5, 2.5);
  EXPECT_EQ(sourcePixelOfRaster(raster, PixelCentre::Integer), glm::dvec2(3, 2));
  EXPECT_EQ(sourcePixelOfRaster(raster, PixelCentre::HalfInteger), raster);
  EXPECT_EQ(rasterOfSourcePixel({3, 2}, PixelCentre::Integer), raster);
  // The wrong convention misses the pixel's OpenCV coordinates by half a pixel.
  EXPECT_NE(sourcePixelOfRaster(raster, PixelCentre::HalfInteger), glm::dvec2(3, 2));
  EXPECT_STREQ(pixelCentreName(PixelCentre::Integer), "integer");
}

TEST(CameraFileConventions, AxisNamesAndPoseChecks) {
  EXPECT_EQ(parseAxisConvention("OpenGL"), AxisConvention::OpenGL);
  EXPECT_STREQ(axisConventionName(AxisConvention::Blender), "blender");
  EXPECT_ERROR_MENTIONS(parseAxisConvention("opengll"), "opengll", "did you mean 'opengl'");
  glm::dmat4 pose(1.0);
  pose[0][0] = 1.00001;
  EXPECT_ERROR_MENTIONS(cvCameraFromWorldOf(pose, AxisConvention::OpenCV, false, "entry X"),
                        "entry X", "not a rotation");
  pose[0][0] = 1.0000001;  // within 1e-6
  EXPECT_NO_THROW(cvCameraFromWorldOf(pose, AxisConvention::OpenCV, false, "entry X"));
  // poseInConvention inverts cvCameraFromWorldOf for every convention, both directions.
  glm::dmat4 cvCameraFromWorld(glm::dvec4(0, 0, -1, 0), glm::dvec4(0, 1, 0, 0),
                               glm::dvec4(1, 0, 0, 0), glm::dvec4(1, 2, 3, 1));
  for (AxisConvention c : {AxisConvention::OpenCV, AxisConvention::OpenGL, AxisConvention::Blender})
    for (bool poseIsWorldFromCamera : {false, true}) {
      const glm::dmat4 back =
          cvCameraFromWorldOf(poseInConvention(cvCameraFromWorld, c, poseIsWorldFromCamera), c,
                              poseIsWorldFromCamera, "t");
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(back[i][j], cvCameraFromWorld[i][j], 1e-15);
    }
}

TEST(CameraFileConventions, SidecarJson) {
  const CalibratedSensor sensor{
      640, 480, Lens(LensModelId::OpenCV, {500, 501, 320, 240, -0.1, 0.01, 0.001, 0.002}),
      PixelCentre::HalfInteger};
  // Camera at world (1, 2, 3) (OpenCV axes = world axes): t = −C.
  glm::dmat4 cvCameraFromWorld(1.0);
  cvCameraFromWorld[3] = glm::dvec4(-1, -2, -3, 1);
  const json j = json::parse(cameraSidecarJson(sensor, cvCameraFromWorld));
  EXPECT_EQ(j["width"], 640);
  EXPECT_EQ(j["model"], "OPENCV");
  EXPECT_EQ(j["pixel_centre"], "half-integer");
  EXPECT_EQ(j["K"], json::parse("[[500, 0, 320], [0, 501, 240], [0, 0, 1]]"));
  EXPECT_EQ(j["params"].get<std::vector<double>>(), sensor.lens.params());
  EXPECT_EQ(j["distortion_opencv"].get<std::vector<double>>(),
            (std::vector<double>{-0.1, 0.01, 0.001, 0.002}));
  EXPECT_EQ(j["world_to_camera_opencv"][0], json::parse("[1, 0, 0, -1]"));
  // OpenGL flips the camera's y and z rows.
  EXPECT_EQ(j["world_to_camera_opengl"][1], json::parse("[0, -1, 0, 2]"));
  EXPECT_EQ(j["world_to_camera_opengl"][2], json::parse("[0, 0, -1, 3]"));
  // camera-to-world holds the camera centre in its last column, in both.
  for (const char* key : {"camera_to_world_opencv", "camera_to_world_opengl"}) {
    EXPECT_EQ(j[key][0][3], 1) << key;
    EXPECT_EQ(j[key][1][3], 2) << key;
    EXPECT_EQ(j[key][2][3], 3) << key;
    EXPECT_EQ(j[key][3], json::parse("[0, 0, 0, 1]")) << key;
  }
  EXPECT_EQ(j["camera_to_world_opengl"][1][1], -1);
}

}  // namespace
}  // namespace aperture
