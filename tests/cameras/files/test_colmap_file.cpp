// COLMAP models (cameras/files/colmap_file.cpp) written here with image ids out of order:
// CameraFile::imageIds lists the ids in the images' order, from text and binary alike. COLMAP
// text and binary parsed from small files written here, with values checked against the text
// of the file and the rotation of a known quaternion; round trips through both writers, text
// and binary giving the same cameras, and every malformed case giving an Error that names the
// file and the entry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "cameras/files/camera_file.h"
#include "cameras/lenses/calibration.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "tests/camera_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::errorOf;

/// Appends `value`'s bytes (x86-64 is little-endian, as COLMAP's binary files).
template <typename T>
void putLittleEndian(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

const char* const kCamerasText =
    "# CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]\n1 PINHOLE 64 48 50 50 32 24\n";

/// Images with ids 7, 3, 12 in that (file) order.
const std::vector<std::pair<uint32_t, std::string>>& modelImages() {
  static const std::vector<std::pair<uint32_t, std::string>> images = {
      {7, "a.png"}, {3, "b.png"}, {12, "c.png"}};
  return images;
}

TEST(PointsFileImageIds, ColmapTextAndBinaryInImageOrder) {
  const std::string dir = test::scratchDir();
  std::filesystem::create_directories(dir + "/text");
  std::filesystem::create_directories(dir + "/bin");
  std::string imagesText = "# IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME\n";
  for (const auto& [id, name] : modelImages())
    imagesText += std::to_string(id) + " 1 0 0 0 0 0 0 1 " + name + "\n\n";
  test::writeFile(dir + "/text/cameras.txt", kCamerasText);
  test::writeFile(dir + "/text/images.txt", imagesText);

  std::string camerasBin, imagesBin;
  putLittleEndian<uint64_t>(camerasBin, 1);
  putLittleEndian<uint32_t>(camerasBin, 1);
  putLittleEndian<int32_t>(camerasBin, 1);  // PINHOLE
  putLittleEndian<uint64_t>(camerasBin, 64);
  putLittleEndian<uint64_t>(camerasBin, 48);
  for (double p : {50.0, 50.0, 32.0, 24.0}) putLittleEndian<double>(camerasBin, p);
  putLittleEndian<uint64_t>(imagesBin, modelImages().size());
  for (const auto& [id, name] : modelImages()) {
    putLittleEndian<uint32_t>(imagesBin, id);
    for (double q : {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}) putLittleEndian<double>(imagesBin, q);
    putLittleEndian<uint32_t>(imagesBin, 1);
    imagesBin += name;
    imagesBin.push_back('\0');
    putLittleEndian<uint64_t>(imagesBin, 0);
  }
  test::writeFile(dir + "/bin/cameras.bin", camerasBin);
  test::writeFile(dir + "/bin/images.bin", imagesBin);

  for (const char* model : {"/text", "/bin"}) {
    const CameraFile file = readCameraFile(dir + model);
    ASSERT_EQ(file.images.size(), 3u) << model;
    ASSERT_EQ(file.imageIds.size(), 3u) << model;
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(file.images[k].name, modelImages()[k].second) << model;
      EXPECT_EQ(file.imageIds[k], std::to_string(modelImages()[k].first)) << model;
    }
  }
}

namespace fs = std::filesystem;
using nlohmann::json;
using test::apply;
using test::expectSameFile;
using test::expectSamePoses;
using test::rc;
using test::readFile;
using test::scratchDir;
using test::writeFile;

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

}  // namespace
}  // namespace aperture
