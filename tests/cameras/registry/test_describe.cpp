// The --describe text (cameras/registry/describe.h): the frame, every renderer's conventions,
// the view volume's corners and the EXR header's matrices as row vectors.
#include <gtest/gtest.h>

#include <string>

#include "cameras/registry/describe.h"
#include "cameras/schema/params.h"

namespace aperture {
namespace {

TEST(CameraDescribe, PrintsFrameConventionsAndCorners) {
  CameraParams p;
  p.eye = {0, 1, 5};
  p.at = glm::dvec3(0, 1, 0);
  p.fovDeg = 60;
  const std::string text = describeCamera(p);
  for (const char* key : {"e = (0, 1, 5)", "W = (0, 0, 1)", "viewport", "fov horizontal", "pbrt-v4",
                          "Mitsuba", "35 mm", "OpenCV", "view volume: frustum", "far top-left"})
    EXPECT_NE(text.find(key), std::string::npos) << key << "\n" << text;
  CameraParams o = p;
  o.type = "orthographic";
  o.viewport = glm::dvec2(2, 1);
  EXPECT_NE(describeCamera(o).find("view volume: box"), std::string::npos);
}

TEST(CameraDescribe, PrintsTheExrHeaderMatricesAsRowVectors) {
  // Eye (0, 1, 5) looking along −z: camera space is x = X, y = Y − 1, z = 5 − Z, so the
  // row-vector matrix has rows (1,0,0,0), (0,1,0,0), (0,0,−1,0) and translation (0,−1,5,1).
  CameraParams p;
  p.eye = {0, 1, 5};
  p.at = glm::dvec3(0, 1, 0);
  p.fovDeg = 60;
  p.width = 40;
  p.height = 30;
  const std::string text = describeCamera(p);
  for (const char* key :
       {"pixelAspectRatio 1,", "+x right, +y up, +z forward", "[0, 0, -1, 0]\n    [0, -1, 5, 1]",
        "worldToNDC (p' = p·M, then divide by w; NDC (0, 0) top-left"})
    EXPECT_NE(text.find(key), std::string::npos) << key << "\n" << text;
  CameraParams e = p;
  e.type = "equirect";
  const std::string panorama = describeCamera(e);
  EXPECT_NE(panorama.find("worldToNDC: none"), std::string::npos) << panorama;
  EXPECT_NE(panorama.find("aperture.equirect.longitudeRange (-180, 180)"), std::string::npos)
      << panorama;
}

}  // namespace
}  // namespace aperture
