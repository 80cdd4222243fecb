// Camera files: every format parsed from small files written here, with values checked against
// the text of the file and against independent computations (the rotation of a known
// quaternion, the focal length of camera_angle_x, which way an OpenGL camera looks); round
// trips through every writer; COLMAP text and binary giving the same cameras; the pixel-centre
// and axis conventions shown to catch a half-pixel slip and an axis flip; and every malformed
// case giving an Error that names the file and the entry.
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
#include "tests/support.h"

namespace aperture {
namespace {

using test::errorOf;

namespace fs = std::filesystem;
using nlohmann::json;
using test::readFile;
using test::scratchDir;
using test::writeFile;

#define EXPECT_ERROR_MENTIONS(call, ...)                                  \
  do {                                                                    \
    const std::string message = errorOf([&] { call; });                   \
    ASSERT_FALSE(message.empty()) << #call " did not throw";              \
    for (const std::string& part : std::vector<std::string>{__VA_ARGS__}) \
      EXPECT_NE(message.find(part), std::string::npos)                    \
          << "'" << part << "' is missing from: " << message;             \
  } while (0)

glm::dvec3 apply(const glm::dmat4& m, const glm::dvec3& p) {
  return glm::dvec3(m * glm::dvec4(p, 1));
}

// Rotation of (row, col) of a GLM matrix, row-major reading.
double rc(const glm::dmat4& m, int row, int col) { return m[col][row]; }

void expectSameFile(const CameraFile& a, const CameraFile& b) {
  ASSERT_EQ(a.sensors.size(), b.sensors.size());
  for (size_t s = 0; s < a.sensors.size(); ++s) {
    EXPECT_TRUE(a.sensors[s] == b.sensors[s]) << "sensor " << s;
    EXPECT_EQ(a.sensors[s].lens.params(), b.sensors[s].lens.params()) << "sensor " << s;
  }
  EXPECT_EQ(a.sensorIds, b.sensorIds);
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t k = 0; k < a.images.size(); ++k) {
    EXPECT_EQ(a.images[k].name, b.images[k].name);
    EXPECT_EQ(a.images[k].sensor, b.images[k].sensor);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        EXPECT_EQ(a.images[k].cvCameraFromWorld[c][r], b.images[k].cvCameraFromWorld[c][r])
            << "image " << k << " (row " << r << ", column " << c << ")";
  }
}

void expectSamePoses(const CameraFile& a, const CameraFile& b, double tolerance) {
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t k = 0; k < a.images.size(); ++k)
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        EXPECT_NEAR(a.images[k].cvCameraFromWorld[c][r], b.images[k].cvCameraFromWorld[c][r],
                    tolerance)
            << "image " << k << " (row " << r << ", column " << c << ")";
}

// ---- COLMAP fixtures ----

// Camera 3: PINHOLE; camera 7: OPENCV. Image 5 looks along +x (a 90° turn about y), image 9
// has the identity rotation. The quaternion (cos 45°, 0, sin 45°, 0) is typed to 17 digits.
const char* kCamerasTxt =
    "# Camera list with one line of data per camera:\n"
    "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
    "3 PINHOLE 640 480 500.25 501.5 320.5 240.25\n"
    "\n"
    "7 OPENCV 800 600 700 710 400 300 -0.125 0.0625 0.001 -0.002\n";
const char* kImagesTxt =
    "# Image list with two lines of data per image:\n"
    "5 0.70710678118654757 0 0.70710678118654757 0 1 2 3 3 left/a.png\n"
    "10.5 20.5 -1 11 12 4\n"
    "9 1 0 0 0 -0.5 0.25 4 7 b.png\n"
    "\n";

std::string colmapTextFolder() {
  const std::string dir = scratchDir() + "/sparse";
  fs::create_directories(dir);
  writeFile(dir + "/cameras.txt", kCamerasTxt);
  writeFile(dir + "/images.txt", kImagesTxt);
  return dir;
}

// A little-endian encoder for the test's own binary files (written independently of the
// reader's decoder, by memcpy on this little-endian host).
struct Bytes {
  std::string s;
  template <typename T>
  Bytes& put(T v) {
    static_assert(std::is_arithmetic_v<T>);
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    s.append(b, sizeof(T));
    return *this;
  }
  Bytes& name(const std::string& n) {
    s += n;
    s.push_back('\0');
    return *this;
  }
};

std::string camerasBin() {
  Bytes b;
  b.put<uint64_t>(2);
  b.put<uint32_t>(3).put<int32_t>(1).put<uint64_t>(640).put<uint64_t>(480);
  for (double p : {500.25, 501.5, 320.5, 240.25}) b.put(p);
  b.put<uint32_t>(7).put<int32_t>(4).put<uint64_t>(800).put<uint64_t>(600);
  for (double p : {700.0, 710.0, 400.0, 300.0, -0.125, 0.0625, 0.001, -0.002}) b.put(p);
  return b.s;
}

std::string imagesBin() {
  Bytes b;
  b.put<uint64_t>(2);
  const double h = 0.70710678118654757;
  b.put<uint32_t>(5);
  for (double v : {h, 0.0, h, 0.0, 1.0, 2.0, 3.0}) b.put(v);
  b.put<uint32_t>(3).name("left/a.png").put<uint64_t>(2);
  b.put(10.5).put(20.5).put<uint64_t>(~uint64_t(0)).put(11.0).put(12.0).put<uint64_t>(4);
  b.put<uint32_t>(9);
  for (double v : {1.0, 0.0, 0.0, 0.0, -0.5, 0.25, 4.0}) b.put(v);
  b.put<uint32_t>(7).name("b.png").put<uint64_t>(0);
  return b.s;
}

std::string colmapBinaryFolder() {
  const std::string dir = scratchDir() + "/sparse_bin";
  fs::create_directories(dir);
  writeFile(dir + "/cameras.bin", camerasBin());
  writeFile(dir + "/images.bin", imagesBin());
  return dir;
}

TEST(CameraFileColmap, TextValuesAreTheFilesAndTheQuaternionsRotation) {
  const CameraFile f = readCameraFile(colmapTextFolder());
  EXPECT_EQ(f.format, CameraFileFormat::ColmapText);
  ASSERT_EQ(f.sensors.size(), 2u);
  EXPECT_EQ(f.sensorIds, (std::vector<std::string>{"3", "7"}));
  EXPECT_EQ(f.sensors[0].width, 640);
  EXPECT_EQ(f.sensors[0].height, 480);
  EXPECT_EQ(f.sensors[0].lens.model(), LensModelId::Pinhole);
  EXPECT_EQ(f.sensors[0].lens.params(), (std::vector<double>{500.25, 501.5, 320.5, 240.25}));
  EXPECT_EQ(f.sensors[0].pixelCentre, PixelCentre::HalfInteger);
  EXPECT_EQ(f.sensors[1].lens.model(), LensModelId::OpenCV);
  EXPECT_EQ(f.sensors[1].lens.params(),
            (std::vector<double>{700, 710, 400, 300, -0.125, 0.0625, 0.001, -0.002}));
  ASSERT_EQ(f.images.size(), 2u);
  EXPECT_EQ(f.images[0].name, "left/a.png");
  EXPECT_EQ(f.images[0].sensor, 0);
  EXPECT_EQ(f.images[1].name, "b.png");
  EXPECT_EQ(f.images[1].sensor, 1);
  // A 90° turn about +y maps x to −z and z to x: R = [0 0 1; 0 1 0; −1 0 0].
  const glm::dmat4& m = f.images[0].cvCameraFromWorld;
  const double expected[3][3] = {{0, 0, 1}, {0, 1, 0}, {-1, 0, 0}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(rc(m, r, c), expected[r][c], 1e-15) << r << c;
  EXPECT_EQ(glm::dvec3(m[3]), glm::dvec3(1, 2, 3));
  // x_cam = R x_world + t: the world point (1, 0, 0) lands at (0, 0, −1) + t.
  const glm::dvec3 p = apply(m, {1, 0, 0});
  EXPECT_NEAR(p.x, 1, 1e-15);
  EXPECT_NEAR(p.y, 2, 1e-15);
  EXPECT_NEAR(p.z, 2, 1e-15);
  EXPECT_EQ(f.images[1].cvCameraFromWorld,
            glm::dmat4(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 1, 0, 0), glm::dvec4(0, 0, 1, 0),
                       glm::dvec4(-0.5, 0.25, 4, 1)));
}

TEST(CameraFileColmap, BinaryGivesTheSameCamerasAsText) {
  const CameraFile text = readCameraFile(colmapTextFolder());
  const CameraFile binary = readCameraFile(colmapBinaryFolder());
  EXPECT_EQ(binary.format, CameraFileFormat::ColmapBinary);
  expectSameFile(text, binary);
}

TEST(CameraFileColmap, AModelFileNamesItsFolder) {
  const std::string dir = colmapTextFolder();
  EXPECT_EQ(readCameraFile(dir + "/images.txt").images.size(), 2u);
}

TEST(CameraFileColmap, WritersRoundTripAndAgree) {
  const CameraFile original = readCameraFile(colmapTextFolder());
  const std::string dir = scratchDir();
  writeColmapText(original, dir + "/text");
  writeColmapBinary(original, dir + "/bin");
  EXPECT_TRUE(fs::exists(dir + "/text/points3D.txt"));
  EXPECT_TRUE(fs::exists(dir + "/bin/points3D.bin"));
  const CameraFile text = readCameraFile(dir + "/text");
  const CameraFile binary = readCameraFile(dir + "/bin");
  // The same quaternions, once as 17-digit text and once as raw doubles: identical files.
  expectSameFile(text, binary);
  // Intrinsics, ids and names are exact; the pose went R → q → R (exact to rounding).
  ASSERT_EQ(text.sensors.size(), original.sensors.size());
  for (size_t s = 0; s < text.sensors.size(); ++s)
    EXPECT_TRUE(text.sensors[s] == original.sensors[s]);
  EXPECT_EQ(text.sensorIds, original.sensorIds);
  expectSamePoses(text, original, 1e-15);
  // What was written reads back and writes out again to the same bytes.
  writeColmapText(text, dir + "/text2");
  writeColmapBinary(binary, dir + "/bin2");
  EXPECT_EQ(readFile(dir + "/text2/cameras.txt"), readFile(dir + "/text/cameras.txt"));
  EXPECT_EQ(readFile(dir + "/bin2/cameras.bin"), readFile(dir + "/bin/cameras.bin"));
}

TEST(CameraFileColmap, HalfTurnsGoThroughEveryQuaternionBranch) {
  // Half turns about x, y and z (trace −1: the largest component is x, y or z in turn) and a
  // turn of 2 rad about (1, 1, 1) survive R → q → R.
  CameraFile f;
  f.sensors = {{8, 8, Lens(LensModelId::SimplePinhole, {4, 4, 4}), PixelCentre::HalfInteger}};
  f.sensorIds = {"1"};
  const auto rotation = [](glm::dvec3 axis, double angle) {
    const glm::dvec3 k = glm::normalize(axis);
    const double c = std::cos(angle), s = std::sin(angle);
    glm::dmat4 m(1.0);
    const double cross[3][3] = {{0, -k.z, k.y}, {k.z, 0, -k.x}, {-k.y, k.x, 0}};
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col)
        m[col][r] = (r == col ? c : 0.0) + (1 - c) * k[r] * k[col] + s * cross[r][col];
    m[3] = glm::dvec4(0.5, -1, 2, 1);
    return m;
  };
  const std::vector<glm::dmat4> poses = {rotation({1, 0, 0}, kPi), rotation({0, 1, 0}, kPi),
                                         rotation({0, 0, 1}, kPi), rotation({1, 1, 1}, 2.0)};
  for (size_t k = 0; k < poses.size(); ++k)
    f.images.push_back({"i" + std::to_string(k) + ".png", 0, poses[k]});
  const std::string dir = scratchDir();
  writeColmapBinary(f, dir);
  expectSamePoses(readCameraFile(dir), f, 1e-15);
}

TEST(CameraFileColmap, ImageLinesSplitAtEveryWhiteSpaceTheTokensDo) {
  // The fields split at any white space, a '\r' inside the line included, and the name is the
  // rest of the line after the ninth field. fuzz_cameras found a line with a '\r' inside
  // (tests/fuzz/regressions/cameras/colmap_carriage_return_inside_an_image_line): the fields
  // split there, and the name's search, which skipped only spaces and tabs, ran off the line's
  // end into std::out_of_range.
  const std::string dir = scratchDir() + "/whitespace";
  fs::create_directories(dir);
  writeFile(dir + "/cameras.txt", "1 PINHOLE 10 10 5 5 5 5\n");
  writeFile(dir + "/images.txt",
            "4 1\t0\v0\f0 0\r0 0 1 my image.png\n\n"
            "6 1 0 0 0\r0 0 0 1 b.png\n\n");
  const CameraFile f = readCameraFile(dir);
  ASSERT_EQ(f.images.size(), 2u);
  EXPECT_EQ(f.imageIds, (std::vector<std::string>{"4", "6"}));
  EXPECT_EQ(f.images[0].name, "my image.png");
  EXPECT_EQ(f.images[1].name, "b.png");
  EXPECT_EQ(f.images[0].cvCameraFromWorld, glm::dmat4(1.0));
}

TEST(CameraFileColmap, MalformedFilesNameTheFileAndTheEntry) {
  const std::string dir = scratchDir();
  const auto textModel = [&](const std::string& name, const std::string& cameras,
                             const std::string& images) {
    const std::string d = dir + "/" + name;
    fs::create_directories(d);
    writeFile(d + "/cameras.txt", cameras);
    writeFile(d + "/images.txt", images);
    return d;
  };
  const std::string goodImage = "1 1 0 0 0 0 0 0 1 a.png\n\n";
  EXPECT_ERROR_MENTIONS(
      readCameraFile(textModel("count", "# c\n1 PINHOLE 10 10 5 5 5\n", goodImage)),
      "cameras.txt line 2", "camera 1", "PINHOLE takes 4 parameters", "got 3");
  EXPECT_ERROR_MENTIONS(readCameraFile(textModel("model", "1 PINHOLEE 10 10 5 5 5 5\n", goodImage)),
                        "cameras.txt line 1", "camera 1", "PINHOLEE", "did you mean 'PINHOLE'");
  EXPECT_ERROR_MENTIONS(readCameraFile(textModel("size", "1 PINHOLE 0 10 5 5 5 5\n", goodImage)),
                        "cameras.txt line 1", "camera 1", "WIDTH");
  EXPECT_ERROR_MENTIONS(readCameraFile(textModel("quat", "1 PINHOLE 10 10 5 5 5 5\n",
                                                 "# x\n4 1 0.1 0 0 0 0 0 1 a.png\n\n")),
                        "images.txt line 2", "image 4", "norm");
  // Within the tolerance the quaternion is normalised.
  EXPECT_NO_THROW(readCameraFile(
      textModel("quat_ok", "1 PINHOLE 10 10 5 5 5 5\n", "4 1.0000001 0 0 0 0 0 0 1 a.png\n\n")));
  EXPECT_ERROR_MENTIONS(readCameraFile(textModel("missing", "1 PINHOLE 10 10 5 5 5 5\n",
                                                 "4 1 0 0 0 0 0 0 2 a.png\n\n")),
                        "images.txt line 1", "image 4", "camera 2");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(textModel("dup", "1 PINHOLE 10 10 5 5 5 5\n",
                               "4 1 0 0 0 0 0 0 1 a.png\n\n5 1 0 0 0 0 0 0 1 a.png\n\n")),
      "images.txt line 3", "image 5", "'a.png' is given twice");
  EXPECT_ERROR_MENTIONS(readCameraFile(textModel("badnum", "1 PINHOLE 10 10 5 5 5 5\n",
                                                 "4 1 0 0 0 0 zero 0 1 a.png\n\n")),
                        "images.txt line 1", "image 4", "TY", "zero");
  EXPECT_ERROR_MENTIONS(
      readCameraFile(
          textModel("dupcam", "1 PINHOLE 10 10 5 5 5 5\n1 PINHOLE 10 10 5 5 5 5\n", goodImage)),
      "cameras.txt line 2", "camera id 1 is given twice");

  const auto binaryModel = [&](const std::string& name, const std::string& cameras,
                               const std::string& images) {
    const std::string d = dir + "/" + name;
    fs::create_directories(d);
    writeFile(d + "/cameras.bin", cameras);
    writeFile(d + "/images.bin", images);
    return d;
  };
  const std::string cams = camerasBin();
  EXPECT_ERROR_MENTIONS(
      readCameraFile(binaryModel("trunc", cams.substr(0, cams.size() - 4), imagesBin())),
      "cameras.bin", "truncated", "parameter p2 of camera 7");
  const std::string ims = imagesBin();
  EXPECT_ERROR_MENTIONS(
      readCameraFile(binaryModel("trunc_points", cams, ims.substr(0, ims.size() - 9))),
      "images.bin", "image 9");
  Bytes huge;
  huge.put<uint64_t>(uint64_t(1) << 40);
  EXPECT_ERROR_MENTIONS(readCameraFile(binaryModel("huge", huge.s, imagesBin())), "cameras.bin",
                        "number of cameras", "more than the remaining");
  Bytes hugePoints;
  hugePoints.put<uint64_t>(1).put<uint32_t>(1);
  for (double v : {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}) hugePoints.put(v);
  hugePoints.put<uint32_t>(3).name("x.png").put<uint64_t>(uint64_t(1) << 60);
  EXPECT_ERROR_MENTIONS(readCameraFile(binaryModel("huge_points", cams, hugePoints.s)),
                        "images.bin", "2D points of image 1", "more than the remaining");
  Bytes badModel;
  badModel.put<uint64_t>(1).put<uint32_t>(2).put<int32_t>(18).put<uint64_t>(8).put<uint64_t>(8);
  for (int k = 0; k < 4; ++k) badModel.put(1.0);
  EXPECT_ERROR_MENTIONS(readCameraFile(binaryModel("model_id", badModel.s, imagesBin())),
                        "cameras.bin", "camera 2", "model id 18");
  Bytes noNul;
  noNul.put<uint64_t>(1).put<uint32_t>(1);
  for (double v : {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}) noNul.put(v);
  noNul.put<uint32_t>(3);
  noNul.s += "name-without-end";
  EXPECT_ERROR_MENTIONS(readCameraFile(binaryModel("no_nul", cams, noNul.s)), "images.bin",
                        "name of image 1", "truncated");
  EXPECT_ERROR_MENTIONS(readCameraFile(dir + "/nothing-here"), "nothing-here");
}

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
