// OpenCV camera files (cameras/files/opencv_file.cpp), JSON and FileStorage YAML, parsed from
// small files written here: values checked against the text of the file (Rodrigues vectors,
// five coefficients), the OpenCV JSON writer's round trip, a conversion between pixel
// conventions keeping the raster position, and unsupported terms and malformed cameras named.
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

// ---- OpenCV ----

TEST(CameraFileOpenCV, JsonWithRodriguesAndFiveCoefficients) {
  const std::string path = scratchDir() + "/calib.json";
  // rvec (0, π/2, 0): a 90° turn about y, R = [0 0 1; 0 1 0; −1 0 0].
  writeFile(path, R"({"name": "cam0", "width": 1280, "height": 720,
    "K": [[900.5, 0, 639.5], [0, 901.25, 359.75], [0, 0, 1]],
    "dist": [-0.2, 0.05, 0.001, -0.001, 0.003],
    "rvec": [0, 1.5707963267948966, 0], "t": [0.1, -0.2, 0.3]})");
  const CameraFile f = readCameraFile(path);
  EXPECT_EQ(f.format, CameraFileFormat::OpenCVJson);
  const CalibratedSensor& s = f.sensors[0];
  EXPECT_EQ(s.pixelCentre, PixelCentre::Integer);
  EXPECT_EQ(s.width, 1280);
  EXPECT_EQ(s.lens.model(), LensModelId::FullOpenCV);
  EXPECT_EQ(s.lens.params(), (std::vector<double>{900.5, 901.25, 639.5, 359.75, -0.2, 0.05, 0.001,
                                                  -0.001, 0.003, 0, 0, 0}));
  EXPECT_EQ(f.images[0].name, "cam0");
  const double expected[3][3] = {{0, 0, 1}, {0, 1, 0}, {-1, 0, 0}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(rc(f.images[0].cvCameraFromWorld, r, c), expected[r][c], 1e-15) << r << c;
  EXPECT_EQ(glm::dvec3(f.images[0].cvCameraFromWorld[3]), glm::dvec3(0.1, -0.2, 0.3));
}

const char* kOpenCVYaml =
    "%YAML:1.0\n"
    "---\n"
    "left:\n"
    "   width: 640\n"
    "   height: 480\n"
    "   K: !!opencv-matrix\n"
    "      rows: 3\n"
    "      cols: 3\n"
    "      dt: d\n"
    "      data: [ 500., 0., 319.5, 0., 500., 239.5, 0., 0., 1. ]\n"
    "   dist: !!opencv-matrix\n"
    "      rows: 1\n"
    "      cols: 4\n"
    "      dt: d\n"
    "      data: [ -0.25, 0.125, 0., 0. ]\n"
    "   R: !!opencv-matrix\n"
    "      rows: 3\n"
    "      cols: 3\n"
    "      dt: d\n"
    "      data: [ 1., 0., 0., 0., 1., 0., 0., 0., 1. ]\n"
    "   t: [ 0.5, 0., 0. ]\n"
    "right:\n"
    "   width: 640\n"
    "   height: 480\n"
    "   K: [ [500, 0, 319.5], [0, 500, 239.5], [0, 0, 1] ]\n"
    "   dist: [ 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 ]\n"
    "   rvec: [ 0, 0, 0 ]\n"
    "   t: [ -0.5, 0, 0 ]\n";

TEST(CameraFileOpenCV, FileStorageYamlCamerasByName) {
  const std::string path = scratchDir() + "/stereo.yaml";
  writeFile(path, kOpenCVYaml);
  const CameraFile f = readCameraFile(path);
  EXPECT_EQ(f.format, CameraFileFormat::OpenCVYaml);
  ASSERT_EQ(f.images.size(), 2u);
  EXPECT_EQ(f.images[0].name, "left");
  EXPECT_EQ(f.images[1].name, "right");
  ASSERT_EQ(f.sensors.size(), 2u);
  EXPECT_EQ(f.sensors[0].lens.model(), LensModelId::OpenCV);
  EXPECT_EQ(f.sensors[0].lens.params(),
            (std::vector<double>{500, 500, 319.5, 239.5, -0.25, 0.125, 0, 0}));
  EXPECT_EQ(f.sensors[1].lens.model(), LensModelId::Pinhole);  // 14 zero coefficients
  EXPECT_EQ(f.images[0].cvCameraFromWorld[3], glm::dvec4(0.5, 0, 0, 1));
  EXPECT_EQ(f.images[1].cvCameraFromWorld,
            glm::dmat4(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 1, 0, 0), glm::dvec4(0, 0, 1, 0),
                       glm::dvec4(-0.5, 0, 0, 1)));
}

TEST(CameraFileOpenCV, UnsupportedTermsAndMalformedCamerasAreNamed) {
  const std::string dir = scratchDir();
  const auto camera = [&](const std::string& name, const std::string& fields) {
    writeFile(dir + "/" + name, R"({"cameras": [{"name": "good", "width": 4, "height": 4,
      "K": [[2,0,2],[0,2,2],[0,0,1]], "R": [[1,0,0],[0,1,0],[0,0,1]], "t": [0,0,0]},
      {"name": "bad", )" + fields + "}]}");
    return dir + "/" + name;
  };
  const std::string pose = R"("R": [[1,0,0],[0,1,0],[0,0,1]], "t": [0,0,0])";
  const std::string k = R"("K": [[2,0,2],[0,2,2],[0,0,1]])";
  EXPECT_ERROR_MENTIONS(
      readCameraFile(camera("prism.json", R"("width": 4, "height": 4, )" + k + ", " + pose +
                                              R"(, "dist": [0.1,0,0,0,0,0,0,0,0.01,0,0,0])")),
      "prism.json", "cameras[1] ('bad')", "s1", "thin-prism");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(camera("tilt.json", R"("width": 4, "height": 4, )" + k + ", " + pose +
                                             R"(, "dist": [0,0,0,0,0,0,0,0,0,0,0,0,0,0.2])")),
      "tilt.json", "'bad'", "τy", "tilt");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(camera(
          "skew.json", R"("width": 4, "height": 4, "K": [[2,0.5,2],[0,2,2],[0,0,1]], )" + pose)),
      "skew.json", "'bad'", "skew");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(camera("six.json", R"("width": 4, "height": 4, )" + k + ", " + pose +
                                            R"(, "dist": [0.1,0,0,0,0,0])")),
      "six.json", "'bad'", "6 coefficients");
  EXPECT_ERROR_MENTIONS(readCameraFile(camera("size.json", k + ", " + pose)), "size.json", "'bad'",
                        "image size");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(camera("rot.json", R"("width": 4, "height": 4, )" + k +
                                            R"(, "R": [[1,0,0],[0,1,0],[0,0,-1]], "t": [0,0,0])")),
      "rot.json", "'bad'", "not a rotation");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(
          camera("dup.json", R"("name": "good", "width": 4, "height": 4, )" + k + ", " + pose)),
      "dup.json", "'good' is given twice");
  // A name that is not UTF-8 (Latin-1 'é') reads, and cannot go into a JSON file: an Error.
  writeFile(dir + "/latin1.yaml",
            "%YAML:1.0\ncaf\xe9:\n  width: 4\n  height: 4\n"
            "  K: [2, 0, 2, 0, 2, 2, 0, 0, 1]\n  rvec: [0, 0, 0]\n"
            "  t: [0, 0, 0]\n  dist: [0, 0, 0, 0, 0x]\n");
  EXPECT_ERROR_MENTIONS(readCameraFile(dir + "/latin1.yaml"), "latin1.yaml", "dist");
  writeFile(dir + "/latin1.yaml",
            "%YAML:1.0\ncaf\xe9:\n  width: 4\n  height: 4\n"
            "  K: [2, 0, 2, 0, 2, 2, 0, 0, 1]\n  rvec: [0, 0, 0]\n"
            "  t: [0, 0, 0]\n");
  const CameraFile latin1 = readCameraFile(dir + "/latin1.yaml");
  EXPECT_EQ(latin1.images[0].name, "caf\xe9");
  EXPECT_ERROR_MENTIONS(writeOpenCVJson(latin1, dir + "/latin1.json"), "latin1.json", "UTF-8");
  writeFile(dir + "/broken.yaml", "%YAML:1.0\nK: [1, 2\n");
  EXPECT_ERROR_MENTIONS(readCameraFile(dir + "/broken.yaml"), "broken.yaml", "YAML");
}

// ---- writers ----

TEST(CameraFileRoundTrip, OpenCVJsonIsExact) {
  const std::string dir = scratchDir();
  writeFile(dir + "/stereo.yaml", kOpenCVYaml);
  const CameraFile original = readCameraFile(dir + "/stereo.yaml");
  writeOpenCVJson(original, dir + "/out/calib.json");
  const CameraFile back = readCameraFile(dir + "/out/calib.json");
  expectSameFile(original, back);
}

TEST(CameraFileRoundTrip, ConvertingBetweenPixelConventionsKeepsTheRasterPosition) {
  // An OpenCV camera (integer centres) written as COLMAP (half-integer): the principal point
  // moves by +½ pixel, so the same ray meets the same raster position.
  const std::string dir = scratchDir();
  writeFile(dir + "/stereo.yaml", kOpenCVYaml);
  const CameraFile cv = readCameraFile(dir + "/stereo.yaml");
  writeColmapText(cv, dir + "/colmap");
  const CameraFile colmap = readCameraFile(dir + "/colmap");
  const Lens& a = cv.sensors[1].lens;  // the pinhole
  const Lens& b = colmap.sensors[1].lens;
  EXPECT_EQ(b.cx(), a.cx() + 0.5);
  const glm::dvec3 ray(0.1, -0.05, 1);
  const glm::dvec2 cvPixel(a.fx() * ray.x / ray.z + a.cx(), a.fy() * ray.y / ray.z + a.cy());
  const glm::dvec2 colmapPixel(b.fx() * ray.x / ray.z + b.cx(), b.fy() * ray.y / ray.z + b.cy());
  EXPECT_EQ(rasterOfSourcePixel(cvPixel, PixelCentre::Integer),
            rasterOfSourcePixel(colmapPixel, PixelCentre::HalfInteger));
  // Taking OpenCV's pixel for a half-integer one slips by half a pixel: caught.
  EXPECT_NE(rasterOfSourcePixel(cvPixel, PixelCentre::HalfInteger),
            rasterOfSourcePixel(colmapPixel, PixelCentre::HalfInteger));
  // And back: the OpenCV file written from COLMAP's cameras is the original.
  writeOpenCVJson(colmap, dir + "/again.json");
  const CameraFile again = readCameraFile(dir + "/again.json");
  EXPECT_TRUE(again.sensors[1] == cv.sensors[1]);
}

}  // namespace
}  // namespace aperture
