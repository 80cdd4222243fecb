// nerfstudio and original NeRF transforms.json (cameras/files/nerf_file.cpp), parsed from small
// files written here: values checked against the text of the file and independent computations
// (the focal length of camera_angle_x, which way an OpenGL camera looks), an OpenGL pose read as
// OpenCV caught, the nerfstudio writer's round trip, and every malformed case giving an Error
// that names the file and the frame.
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

// ---- nerfstudio / NeRF ----

// The camera at (0, 0, 5) with OpenGL axes aligned to the world: it looks down −z at the
// origin, its up is +y.
const char* kNerfstudioJson = R"({
  "camera_model": "OPENCV",
  "fl_x": 600.5, "fl_y": 601.25, "cx": 320.5, "cy": 240.75, "w": 640, "h": 480,
  "k1": -0.1, "k2": 0.02, "p1": 0.001, "p2": -0.0005,
  "frames": [
    {"file_path": "images/frame_00001.png",
     "transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 5], [0, 0, 0, 1]]},
    {"file_path": "images/frame_00002.png",
     "transform_matrix": [[0, 0, 1, 5], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1]]}
  ]
})";

TEST(CameraFileNerf, NerfstudioValuesAndTheOpenGLAxes) {
  const std::string path = scratchDir() + "/transforms.json";
  writeFile(path, kNerfstudioJson);
  const CameraFile f = readCameraFile(path);
  EXPECT_EQ(f.format, CameraFileFormat::Nerfstudio);
  ASSERT_EQ(f.sensors.size(), 1u);
  EXPECT_EQ(f.sensors[0].lens.model(), LensModelId::OpenCV);
  EXPECT_EQ(f.sensors[0].lens.params(),
            (std::vector<double>{600.5, 601.25, 320.5, 240.75, -0.1, 0.02, 0.001, -0.0005}));
  EXPECT_EQ(f.sensors[0].pixelCentre, PixelCentre::HalfInteger);
  ASSERT_EQ(f.images.size(), 2u);
  for (const CalibratedImage& im : f.images) {
    // The origin is 5 in front (OpenCV: z > 0); a point above it (+y world, the cameras' up)
    // is up in the image (OpenCV: y < 0).
    const glm::dvec3 origin = apply(im.cvCameraFromWorld, {0, 0, 0});
    EXPECT_NEAR(origin.z, 5, 1e-15) << im.name;
    EXPECT_NEAR(origin.x, 0, 1e-15) << im.name;
    const glm::dvec3 above = apply(im.cvCameraFromWorld, {0, 1, 0});
    EXPECT_LT(above.y, 0) << im.name;
    EXPECT_NEAR(above.z, 5, 1e-15) << im.name;
  }
  // The second camera sits at (5, 0, 0) looking along −x; its x axis (the first column) is
  // (0, 0, −1), so a point at world z = −1 is right of the image centre (x > 0).
  EXPECT_GT(apply(f.images[1].cvCameraFromWorld, {0, 0, -1}).x, 0);
}

TEST(CameraFileNerf, ReadingOpenGLPosesAsOpenCVWouldBeCaught) {
  // The same worldFromCamera read with the wrong axes puts the scene behind the camera: the check
  // that a world point in front has z > 0 fails for the wrong convention.
  const glm::dmat4 worldFromCamera(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 1, 0, 0),
                                   glm::dvec4(0, 0, 1, 0), glm::dvec4(0, 0, 5, 1));
  const glm::dvec3 right =
      apply(cvCameraFromWorldOf(worldFromCamera, AxisConvention::OpenGL, true, "t"), {0, 0, 0});
  const glm::dvec3 wrong =
      apply(cvCameraFromWorldOf(worldFromCamera, AxisConvention::OpenCV, true, "t"), {0, 0, 0});
  EXPECT_GT(right.z, 0);
  EXPECT_LT(wrong.z, 0);
  EXPECT_EQ(cvCameraFromWorldOf(worldFromCamera, AxisConvention::Blender, true, "t"),
            cvCameraFromWorldOf(worldFromCamera, AxisConvention::OpenGL, true, "t"));
}

// nerfstudio's perspective distortion (camera_utils.py) and COLMAP's FULL_OPENCV, each
// written out here, agree at a few points when k3 goes to FULL_OPENCV's k3.
glm::dvec2 nerfstudioDistort(const double k[4], const double p[2], glm::dvec2 u) {
  const double r2 = u.x * u.x + u.y * u.y;
  const double d = 1 + r2 * (k[0] + r2 * (k[1] + r2 * (k[2] + r2 * k[3])));
  return {d * u.x + 2 * p[0] * u.x * u.y + p[1] * (r2 + 2 * u.x * u.x),
          d * u.y + 2 * p[1] * u.x * u.y + p[0] * (r2 + 2 * u.y * u.y)};
}
glm::dvec2 fullOpenCVDistort(const std::vector<double>& q, glm::dvec2 u) {
  // q = fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6
  const double r2 = u.x * u.x + u.y * u.y;
  const double radial = (1 + q[4] * r2 + q[5] * r2 * r2 + q[8] * r2 * r2 * r2) /
                        (1 + q[9] * r2 + q[10] * r2 * r2 + q[11] * r2 * r2 * r2);
  return {u.x * radial + 2 * q[6] * u.x * u.y + q[7] * (r2 + 2 * u.x * u.x),
          u.y * radial + 2 * q[7] * u.x * u.y + q[6] * (r2 + 2 * u.y * u.y)};
}

TEST(CameraFileNerf, K3GoesToFullOpenCVWhereTheFormulasCoincideAndK4IsRefused) {
  const std::string dir = scratchDir();
  writeFile(dir + "/k3.json", R"({"fl_x": 500, "fl_y": 500, "cx": 50, "cy": 40, "w": 100, "h": 80,
    "k1": 0.1, "k2": -0.05, "k3": 0.01, "p1": 0.002, "p2": 0.003,
    "frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  const CameraFile f = readCameraFile(dir + "/k3.json");
  const Lens& lens = f.sensors[0].lens;
  ASSERT_EQ(lens.model(), LensModelId::FullOpenCV);
  const double k[4] = {0.1, -0.05, 0.01, 0}, p[2] = {0.002, 0.003};
  for (glm::dvec2 u : {glm::dvec2(0.3, -0.2), glm::dvec2(-0.5, 0.4), glm::dvec2(0.1, 0.7)}) {
    const glm::dvec2 a = nerfstudioDistort(k, p, u), b = fullOpenCVDistort(lens.params(), u);
    EXPECT_NEAR(a.x, b.x, 1e-15);
    EXPECT_NEAR(a.y, b.y, 1e-15);
  }
  writeFile(dir + "/k4.json", R"({"fl_x": 500, "w": 100, "h": 80, "k1": 0.1, "k4": 0.01,
    "frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  EXPECT_ERROR_MENTIONS(readCameraFile(dir + "/k4.json"), "k4.json", "frame 0", "'a.png'", "k4");
}

TEST(CameraFileNerf, CameraAngleXGivesTheClosedFormFocalLength) {
  const std::string path = scratchDir() + "/transforms_train.json";
  writeFile(path, R"({"camera_angle_x": 0.6911112070083618, "w": 800, "h": 600,
    "frames": [{"file_path": "./train/r_0", "rotation": 0.012566370614359171,
      "transform_matrix": [[-0.9999021887779236, 0.004192245192825794, -0.013345719315111637,
        -0.05379832163453102], [-0.013988681137561798, -0.2996590733528137, 0.95394366979599,
        3.845470428466797], [-4.656612873077393e-10, 0.9540371894836426, 0.29968830943107605,
        1.2080823183059692], [0.0, 0.0, 0.0, 1.0]]}]})");
  const CameraFile f = readCameraFile(path);
  EXPECT_EQ(f.format, CameraFileFormat::InstantNgp);
  const Lens& lens = f.sensors[0].lens;
  EXPECT_EQ(lens.model(), LensModelId::Pinhole);
  // fx = (w / 2) / tan(angle / 2); fy = fx; principal point at the image centre.
  const double fx = 400 / std::tan(0.6911112070083618 / 2);
  EXPECT_NEAR(lens.fx(), fx, 1e-9);
  EXPECT_NEAR(lens.fx(), 1111.1110311937682, 1e-6);  // the NeRF synthetic scenes' focal length
  EXPECT_EQ(lens.fy(), lens.fx());
  EXPECT_EQ(lens.cx(), 400);
  EXPECT_EQ(lens.cy(), 300);
  EXPECT_EQ(f.images[0].name, "./train/r_0");
}

TEST(CameraFileNerf, ImageSizeComesFromTheImageFile) {
  const std::string dir = scratchDir();
  fs::create_directories(dir + "/train");
  {
    const std::vector<unsigned char> pixels(7 * 5 * 3, 128);
    const std::vector<unsigned char> png =
        encodeImage("r_0.png", {7, 5, 3, SampleType::UInt8, pixels.data(), {}, {}});
    writeFile(dir + "/train/r_0.png", std::string(png.begin(), png.end()));
  }
  const std::string identity = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
  writeFile(dir + "/transforms.json", R"({"camera_angle_x": 1.0,
    "frames": [{"file_path": "./train/r_0", "transform_matrix": )" +
                                          identity + "}]}");
  const CameraFile f = readCameraFile(dir + "/transforms.json");
  EXPECT_EQ(f.sensors[0].width, 7);
  EXPECT_EQ(f.sensors[0].height, 5);
  EXPECT_NEAR(f.sensors[0].lens.fx(), 3.5 / std::tan(0.5), 1e-12);
  writeFile(dir + "/missing.json", R"({"camera_angle_x": 1.0,
    "frames": [{"file_path": "./train/r_0", "transform_matrix": )" +
                                       identity +
                                       R"(}, {"file_path": "./train/r_1", "transform_matrix": )" +
                                       identity + "}]}");
  EXPECT_ERROR_MENTIONS(readCameraFile(dir + "/missing.json"), "missing.json", "frame 1",
                        "./train/r_1", "image size");
}

TEST(CameraFileNerf, PerFrameIntrinsicsMakeSensorsAndTheTopLevelWins) {
  const std::string path = scratchDir() + "/transforms.json";
  writeFile(path, R"({"w": 64, "h": 48, "cx": 32, "cy": 24,
    "frames": [
      {"file_path": "a", "fl_x": 50, "fl_y": 50, "cx": 1, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
      {"file_path": "b", "fl_x": 60, "fl_y": 61, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
      {"file_path": "c", "fl_x": 50, "fl_y": 50, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  const CameraFile f = readCameraFile(path);
  ASSERT_EQ(f.sensors.size(), 2u);
  EXPECT_EQ(f.images[0].sensor, 0);
  EXPECT_EQ(f.images[1].sensor, 1);
  EXPECT_EQ(f.images[2].sensor, 0);
  EXPECT_EQ(f.sensors[0].lens.cx(), 32);  // the frame's cx = 1 is ignored, as nerfstudio does
  EXPECT_EQ(f.sensors[1].lens.fy(), 61);
}

TEST(CameraFileNerf, MalformedFilesNameTheFileAndTheFrame) {
  const std::string dir = scratchDir();
  const auto nerf = [&](const std::string& name, const std::string& top, const std::string& frame) {
    writeFile(dir + "/" + name, "{" + top + R"(, "frames": [{"file_path": "ok", "transform_matrix":
      [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}, )" +
                                    frame + "]}");
    return dir + "/" + name;
  };
  const std::string top = R"("fl_x": 10, "w": 8, "h": 6)";
  EXPECT_ERROR_MENTIONS(
      readCameraFile(nerf(
          "scale.json", top,
          R"({"file_path": "x", "transform_matrix": [[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]]})")),
      "scale.json", "frame 1", "'x'", "not a rotation");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(nerf(
          "mirror.json", top,
          R"({"file_path": "x", "transform_matrix": [[-1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]})")),
      "mirror.json", "frame 1", "det = -1");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(nerf(
          "row.json", top,
          R"({"file_path": "x", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,1,1]]})")),
      "row.json", "frame 1", "last row");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(nerf(
          "dup.json", top,
          R"({"file_path": "ok", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]})")),
      "dup.json", "frame 1", "'ok' is given twice");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(nerf(
          "model.json", R"("camera_model": "OPENCV_FISHEYEE", )" + top,
          R"({"file_path": "x", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]})")),
      "model.json", "frame 0", "OPENCV_FISHEYEE", "did you mean 'OPENCV_FISHEYE'");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(nerf(
          "fisheye_p.json", R"("camera_model": "OPENCV_FISHEYE", "p1": 0.1, )" + top,
          R"({"file_path": "x", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]})")),
      "fisheye_p.json", "frame 0", "p1");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(nerf(
          "nofocal.json", R"("w": 8, "h": 6)",
          R"({"file_path": "x", "fl_x": 3, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]})")),
      "nofocal.json", "frame 0", "'ok'", "fl_x");
  writeFile(dir + "/broken.json", "{\"frames\": [");
  EXPECT_ERROR_MENTIONS(readCameraFile(dir + "/broken.json"), "broken.json", "not valid JSON");
}

// ---- writers ----

TEST(CameraFileRoundTrip, NerfstudioIsExactButForTheRoundedTranslation) {
  const std::string dir = scratchDir();
  writeFile(dir + "/transforms.json", kNerfstudioJson);
  const CameraFile original = readCameraFile(dir + "/transforms.json");
  writeNerfstudioJson(original, dir + "/out/transforms.json");
  const CameraFile back = readCameraFile(dir + "/out/transforms.json");
  ASSERT_EQ(back.sensors.size(), original.sensors.size());
  EXPECT_TRUE(back.sensors[0] == original.sensors[0]);
  ASSERT_EQ(back.images.size(), original.images.size());
  for (size_t k = 0; k < back.images.size(); ++k) {
    EXPECT_EQ(back.images[k].name, original.images[k].name);
    EXPECT_EQ(glm::dmat3(back.images[k].cvCameraFromWorld),
              glm::dmat3(original.images[k].cvCameraFromWorld));
  }
  expectSamePoses(back, original, 1e-14);

  // Several sensors (and models) go per frame; every model nerfstudio names comes back.
  CameraFile many = original;
  many.sensors = {
      {64, 48, Lens(LensModelId::SimpleRadial, {50, 32, 24, 0.1}), PixelCentre::HalfInteger},
      {64, 48, Lens(LensModelId::FullOpenCV, {50, 51, 32, 24, 0.1, 0.2, 0.01, 0.02, 0.3, 0, 0, 0}),
       PixelCentre::HalfInteger}};
  many.sensorIds = {"1", "2"};
  many.images[1].sensor = 1;
  writeNerfstudioJson(many, dir + "/many.json");
  const CameraFile manyBack = readCameraFile(dir + "/many.json");
  ASSERT_EQ(manyBack.sensors.size(), 2u);
  EXPECT_TRUE(manyBack.sensors[0] == many.sensors[0]);
  EXPECT_TRUE(manyBack.sensors[1] == many.sensors[1]);

  // A fisheye among perspective lenses cannot share a nerfstudio file.
  many.sensors[1].lens = Lens(LensModelId::OpenCVFisheye, {50, 50, 32, 24, 0.1, 0, 0, 0});
  EXPECT_ERROR_MENTIONS(writeNerfstudioJson(many, dir + "/mixed.json"), "mixed.json", "fisheye");
}

}  // namespace
}  // namespace aperture
