// Camera files on the command line, through the `aperture` binary: the one-line batch form
// (`batch --mesh --cameras --out`), `render --cameras --image`, job files with "cameras":
// {"from"} and {image}, the camera sidecars and the COLMAP model of a batch, `--resume` after a
// lens change, the lens attributes of the EXR header and `camera --describe` (`camera --export`
// is in test_camera_files_cli_export.cpp).
//
// The input camera files are written here as text, so every expected value comes from that
// text and closed forms: the rotation of a quaternion, OpenCV's distortion formula (written out
// here, not taken from the renderer), K of a lecture camera from --fov / --viewport / --shift.
// Every hit pixel's position P (EXR channel P) is projected through the input camera and must
// land on the pixel's centre in the file's pixel convention (COLMAP (j + ½, i + ½), OpenCV
// (j, i)); the other convention is computed too and must miss by half a pixel.
#include <Imath/ImathMatrix.h>
#include <Imath/ImathVec.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfMatrixAttribute.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "core/exr/exr.h"
#include "core/util/units.h"
#include "tests/camera_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::apertureBinary;
using test::expectRefused;
using test::runCommand;

using test::kMaxPixelError;
constexpr double kPoseTolerance = 1e-12;

using Mat3 = std::array<std::array<double, 3>, 3>;
using Vec3 = std::array<double, 3>;

/// One camera of the COLMAP model below: its sensor as cameras.txt gives it and its pose as
/// images.txt gives it (R from the quaternion, worked out by hand).
struct InputCamera {
  std::string name;   ///< NAME in images.txt
  std::string model;  ///< PINHOLE or OPENCV
  int width, height;
  std::vector<double> params;  ///< COLMAP order: fx fy cx cy [k1 k2 p1 p2]
  Mat3 R;                      ///< world-to-camera rotation, OpenCV axes
  Vec3 t;                      ///< world-to-camera translation
  Vec3 centre;                 ///< camera centre −Rᵀt
  double pixelCentre;          ///< where the file puts pixel (i, j)'s centre: j + this, i + this
};

const Mat3 kIdentity = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
// The quaternion (w, x, y, z) = (√½, 0, √½, 0): 90° about +y, x -> −z, z -> x.
const Mat3 kQuarterTurnY = {{{0, 0, 1}, {0, 1, 0}, {-1, 0, 0}}};

// Sensor 1 is a pinhole, sensor 2 OpenCV's standard model with k1 = −0.3 (its radius
// ρ(r) = r(1 + k1 r²) folds at r = 1/√(−3 k1)). Two images of sensor 1, one of sensor 2; all
// three look at the unit sphere at the origin from distance 5 (t = (0, 0, 5)).
const InputCamera kLeft = {"left/0001.jpg", "PINHOLE", 32,         24, {40, 42, 16.5, 11.75},
                           kIdentity,       {0, 0, 5}, {0, 0, -5}, 0.5};
const InputCamera kRight = {
    "right/0001.jpg", "OPENCV",  32,         24, {38, 39, 15.25, 12.5, -0.3, 0, 0.001, -0.002},
    kIdentity,        {0, 0, 5}, {0, 0, -5}, 0.5};
const InputCamera kTop = {"top.png",     "PINHOLE", 32,        24, {40, 42, 16.5, 11.75},
                          kQuarterTurnY, {0, 0, 5}, {5, 0, 0}, 0.5};
const char* const kSphere = "'procedural:sphere?segments=96&rings=48'";

std::string colmapModel(const std::string& dir) {
  fs::create_directories(dir);
  test::writeFile(dir + "/cameras.txt",
                  "# CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]\n"
                  "1 PINHOLE 32 24 40 42 16.5 11.75\n"
                  "2 OPENCV 32 24 38 39 15.25 12.5 -0.3 0 0.001 -0.002\n");
  test::writeFile(dir + "/images.txt",
                  "# IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then the 2D points\n"
                  "1 1 0 0 0 0 0 5 1 left/0001.jpg\n"
                  "\n"
                  "2 1 0 0 0 0 0 5 2 right/0001.jpg\n"
                  "\n"
                  "3 0.70710678118654752 0 0.70710678118654752 0 0 0 5 1 top.png\n"
                  "\n");
  return dir;
}

/// OpenCV's projection (docs.opencv.org, calib3d): x' = X/Z, y' = Y/Z, r² = x'² + y'²,
/// x'' = x'(1 + k1 r² + k2 r⁴) + 2 p1 x'y' + p2 (r² + 2x'²), y'' likewise with p1 and p2
/// exchanged; u = fx x'' + cx, v = fy y'' + cy. PINHOLE is the case without coefficients.
std::array<double, 2> projectInput(const InputCamera& c, const Vec3& world) {
  Vec3 x{};
  for (int r = 0; r < 3; ++r)
    x[size_t(r)] = c.R[size_t(r)][0] * world[0] + c.R[size_t(r)][1] * world[1] +
                   c.R[size_t(r)][2] * world[2] + c.t[size_t(r)];
  double u = x[0] / x[2], v = x[1] / x[2];
  if (c.params.size() == 8) {
    const double k1 = c.params[4], k2 = c.params[5], p1 = c.params[6], p2 = c.params[7];
    const double r2 = u * u + v * v, radial = 1 + k1 * r2 + k2 * r2 * r2;
    const double du = 2 * p1 * u * v + p2 * (r2 + 2 * u * u);
    const double dv = p1 * (r2 + 2 * v * v) + 2 * p2 * u * v;
    u = u * radial + du;
    v = v * radial + dv;
  }
  return {c.params[0] * u + c.params[2], c.params[1] * v + c.params[3]};
}

/// The largest distance, over the hit pixels of `fb`, between P projected through the input
/// camera and the centre of its pixel placed at (j + offset, i + offset).
double maxProjectionError(const Framebuffer& fb, const InputCamera& c, double offset, int* hits) {
  double worst = 0;
  *hits = test::forEachHit(fb, [&](int i, int j, const Imath::V3d& p, double, double) {
    const auto uv = projectInput(c, {p.x, p.y, p.z});
    worst = std::max(worst, std::hypot(uv[0] - (j + offset), uv[1] - (i + offset)));
  });
  return worst;
}

/// The EXR rendered from `c`: right size, the sphere fills part of it, and every hit pixel's P
/// projects through `c` onto its pixel centre, in c's convention and not in the other one.
void expectRenderedBy(const std::string& exr, const InputCamera& c) {
  SCOPED_TRACE(exr + " from " + c.name);
  ASSERT_TRUE(test::fileExists(exr));
  const Framebuffer fb = readExr(exr);
  ASSERT_EQ(fb.width, c.width);
  ASSERT_EQ(fb.height, c.height);
  ASSERT_FALSE(fb.position.empty()) << "render with the position AOV";
  int hits = 0;
  EXPECT_LT(maxProjectionError(fb, c, c.pixelCentre, &hits), kMaxPixelError);
  EXPECT_GT(hits, c.width * c.height / 20) << "the camera should see the sphere";
  EXPECT_LT(hits, c.width * c.height) << "and the sky around it";
  int same = 0;
  EXPECT_GT(maxProjectionError(fb, c, 0.5 - c.pixelCentre, &same), 0.4)
      << "the other pixel-centre convention must be caught";
}

std::string sidecarOf(const std::string& exr) {
  return fs::path(exr).replace_extension(".camera.json").string();
}

/// The sidecar of an image rendered from `c`: K, the lens and the pose are the input's.
void expectSidecarOf(const std::string& exr, const InputCamera& c) {
  SCOPED_TRACE(sidecarOf(exr));
  ASSERT_TRUE(test::fileExists(sidecarOf(exr)));
  const json j = json::parse(test::readFile(sidecarOf(exr)));
  EXPECT_EQ(j["width"], c.width);
  EXPECT_EQ(j["height"], c.height);
  EXPECT_EQ(j["model"], c.model);
  EXPECT_EQ(j["pixel_centre"], "half-integer");
  EXPECT_EQ(j["params"].get<std::vector<double>>(), c.params);
  const double fx = c.params[0], fy = c.params[1], cx = c.params[2], cy = c.params[3];
  EXPECT_EQ(j["K"], json({{fx, 0.0, cx}, {0.0, fy, cy}, {0.0, 0.0, 1.0}}));
  if (c.model == "OPENCV") {
    EXPECT_EQ(j["distortion_opencv"].get<std::vector<double>>(),
              std::vector<double>(c.params.begin() + 4, c.params.end()));
  }
  const json& cvCameraFromWorld = j["world_to_camera_opencv"];
  for (size_t r = 0; r < 3; ++r) {
    for (size_t k = 0; k < 3; ++k)
      EXPECT_NEAR(cvCameraFromWorld[r][k].get<double>(), c.R[r][k], kPoseTolerance) << r << k;
    EXPECT_NEAR(cvCameraFromWorld[r][3].get<double>(), c.t[r], kPoseTolerance) << r;
  }
  EXPECT_EQ(cvCameraFromWorld[3], json({0.0, 0.0, 0.0, 1.0}));
  for (size_t r = 0; r < 3; ++r)
    EXPECT_NEAR(j["camera_to_world_opencv"][r][3].get<double>(), c.centre[r], kPoseTolerance);
}

/// The sensor and pose of a camera file's image are `c`'s.
void expectSameCamera(const CameraFile& file, const CalibratedImage& image, const InputCamera& c) {
  SCOPED_TRACE(image.name + " against " + c.name);
  const CalibratedSensor& s = file.sensors.at(size_t(image.sensor));
  EXPECT_EQ(s.width, c.width);
  EXPECT_EQ(s.height, c.height);
  EXPECT_EQ(s.lens.info().name, c.model);
  EXPECT_EQ(s.lens.params(), c.params);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(image.cvCameraFromWorld[k][r], c.R[size_t(r)][size_t(k)], kPoseTolerance);
    EXPECT_NEAR(image.cvCameraFromWorld[3][r], c.t[size_t(r)], kPoseTolerance);
  }
}

std::string batchOneLine(const std::string& model, const std::string& out,
                         const std::string& extra = "") {
  return apertureBinary() + " batch --quiet --mesh " + kSphere + " --cameras " + model + " --out " +
         out + " --aov depth,position" + extra;
}

// ---- the one-line batch form ----

TEST(CameraFilesCliBatch, OneLineFormRendersEveryImageWithSidecarsAndAColmapModel) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  const std::string out = dir + "/out";
  std::string log;
  ASSERT_EQ(runCommand(batchOneLine(model, out), &log), 0) << log;
  // The image names with .exr, subfolders kept.
  const std::pair<std::string, const InputCamera*> rendered[] = {
      {"left/0001.exr", &kLeft}, {"right/0001.exr", &kRight}, {"top.exr", &kTop}};
  for (const auto& [name, camera] : rendered) {
    expectRenderedBy(out + "/" + name, *camera);
    expectSidecarOf(out + "/" + name, *camera);
  }
  // sparse/: the COLMAP model of what was rendered, named by the EXRs, with the input's
  // sensors (one per distinct sensor) and poses.
  ASSERT_TRUE(fs::is_regular_file(out + "/sparse/cameras.txt"));
  const CameraFile sparse = readCameraFile(out + "/sparse");
  EXPECT_EQ(sparse.format, CameraFileFormat::ColmapText);
  EXPECT_EQ(sparse.sensors.size(), 2u);
  ASSERT_EQ(sparse.images.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(sparse.images[k].name, rendered[k].first);
    expectSameCamera(sparse, sparse.images[k], *rendered[k].second);
  }
  EXPECT_EQ(sparse.images[0].sensor, sparse.images[2].sensor) << "left and top share a camera";
}

TEST(CameraFilesCliBatch, ImageSelectsAndAnUnknownNameGetsDidYouMean) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  const std::string out = dir + "/out";
  std::string log;
  ASSERT_EQ(runCommand(batchOneLine(model, out, " --image top.png --image right/0001.jpg"), &log),
            0)
      << log;
  expectRenderedBy(out + "/right/0001.exr", kRight);
  expectRenderedBy(out + "/top.exr", kTop);
  EXPECT_FALSE(fs::exists(out + "/left")) << "left/0001.jpg was not asked for";
  const CameraFile sparse = readCameraFile(out + "/sparse");
  ASSERT_EQ(sparse.images.size(), 2u);  // in the order of the --image flags
  EXPECT_EQ(sparse.images[0].name, "top.exr");
  EXPECT_EQ(sparse.images[1].name, "right/0001.exr");

  const std::string out2 = dir + "/out2";
  expectRefused(batchOneLine(model, out2, " --image rigth/0001.jpg"),
                {"rigth/0001.jpg", "did you mean 'right/0001.jpg'"}, dir);
  EXPECT_FALSE(fs::exists(out2));
}

TEST(CameraFilesCliBatch, IncompleteOrAmbiguousCommandLinesAreRefusedAndWriteNothing) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  const std::string out = dir + "/out", job = dir + "/job.json";
  test::writeFile(job, R"({"scene": {"meshes": [{"path": "procedural:sphere"}]},
    "cameras": [{"name": "a", "eye": [0, 0, 5], "at": [0, 0, 0]}], "size": [8, 8],
    "output": "jobout/{camera}.exr"})");
  const std::string b = apertureBinary() + " batch --quiet ";
  // Run from `dir`, so that anything written relative to the current directory is seen.
  const std::string cd = "cd '" + dir + "' && ";
  expectRefused(cd + b + "--cameras " + model + " --out " + out, {"--mesh"}, dir);
  expectRefused(cd + b + "--cameras " + model + " --mesh procedural:sphere", {"--out"}, dir);
  expectRefused(cd + b + job + " --cameras " + model + " --mesh procedural:sphere --out " + out,
                {"not both"}, dir);
  expectRefused(cd + b + "--mesh procedural:sphere --out " + out, {"--cameras"}, dir);
  EXPECT_FALSE(fs::exists(out));
}

TEST(CameraFilesCliBatch, ResumeRendersAgainWhenOnlyADistortionCoefficientChanged) {
  // p1 moves pixels but neither the valid region (radial only) nor the frame, d, viewport or
  // shift: only the lens attributes of the header tell the two files apart.
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  const std::string out = dir + "/out", exr = out + "/right/0001.exr";
  const std::string image = " --image right/0001.jpg";
  std::string log;
  ASSERT_EQ(runCommand(batchOneLine(model, out, image), &log), 0) << log;
  const std::string resume = apertureBinary() + " batch --mesh " + kSphere + " --cameras " + model +
                             " --out " + out + " --aov depth,position --resume" + image;
  ASSERT_EQ(runCommand(resume, &log), 0) << log;
  EXPECT_NE(log.find("1 of 1 images up to date"), std::string::npos) << log;
  std::string cameras = test::readFile(model + "/cameras.txt");
  const std::string p1 = " 0.001 ";
  ASSERT_NE(cameras.find(p1), std::string::npos);
  cameras.replace(cameras.find(p1), p1.size(), " 0.004 ");
  test::writeFile(model + "/cameras.txt", cameras);
  ASSERT_EQ(runCommand(resume, &log), 0) << log;
  EXPECT_NE(log.find("stale: camera lens OPENCV"), std::string::npos) << log;
  EXPECT_NE(log.find("0 of 1 images up to date, 1 stale"), std::string::npos) << log;
  InputCamera changed = kRight;
  changed.params[6] = 0.004;
  expectRenderedBy(exr, changed);
  expectSidecarOf(exr, changed);
}

// ---- render --cameras --image ----

TEST(CameraFilesCliRender, RendersTheNamedImageOfTheFile) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  std::string log;
  ASSERT_EQ(
      runCommand(apertureBinary() + " render --quiet --mesh " + kSphere + " --cameras " + model +
                     " --image right/0001.jpg --aov depth,position --out " + dir + "/r.exr",
                 &log),
      0)
      << log;
  expectRenderedBy(dir + "/r.exr", kRight);
  ASSERT_EQ(
      runCommand(apertureBinary() + " render --quiet --mesh " + kSphere + " --cameras " + model +
                     "/images.txt --image top.png --aov depth,position --out " + dir + "/t.exr",
                 &log),
      0)
      << log;
  expectRenderedBy(dir + "/t.exr", kTop);
  EXPECT_FALSE(test::fileExists(dir + "/r.camera.json")) << "render writes no sidecar";
}

TEST(CameraFilesCliRender, AnOpenCVFilePutsPixelCentresOnIntegers) {
  // One camera, so no --image is needed. K's principal point (15.5, 11.5) is the image centre
  // in OpenCV's convention; read as COLMAP's it would be half a pixel up and left.
  const std::string dir = test::scratchDir(), file = dir + "/cam.json";
  test::writeFile(file, R"({"name": "cv0", "width": 32, "height": 24,
    "K": [[40, 0, 15.5], [0, 41, 11.5], [0, 0, 1]], "dist": [0, 0, 0, 0, 0],
    "R": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "t": [0.25, 0, 5]})");
  const InputCamera cv = {"cv0",        "PINHOLE",      32, 24, {40, 41, 15.5, 11.5}, kIdentity,
                          {0.25, 0, 5}, {-0.25, 0, -5}, 0.0};
  std::string log;
  ASSERT_EQ(runCommand(apertureBinary() + " render --quiet --mesh " + kSphere + " --cameras " +
                           file + " --aov depth,position --out " + dir + "/cv.exr",
                       &log),
            0)
      << log;
  expectRenderedBy(dir + "/cv.exr", cv);
}

TEST(CameraFilesCliRender, SeveralImagesNeedImageAndImageNeedsCameras) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  const std::string r =
      apertureBinary() + " render --quiet --mesh procedural:sphere --out " + dir + "/x.exr ";
  expectRefused(r + "--cameras " + model, {"3 images", "--image"}, dir);
  expectRefused(r + "--image top.png", {"--image needs --cameras"}, dir);
  expectRefused(r + "--cameras " + model + " --image left/0001.jpg --image top.png",
                {"--image", "one image"}, dir);
  expectRefused(r + "--cameras " + model + " --image Top.png", {"did you mean 'top.png'"}, dir);
}

TEST(CameraFilesCliRender, FlagsOnTheCommandLineOverrideTheFile) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  const std::string r = apertureBinary() + " render --quiet --mesh " + kSphere + " --cameras " +
                        model + " --image left/0001.jpg --aov depth,position ";
  std::string log;
  ASSERT_EQ(runCommand(r + "--out " + dir + "/spp1.exr", &log), 0) << log;
  ASSERT_EQ(runCommand(r + "--spp 4 --out " + dir + "/spp4.exr", &log), 0) << log;
  EXPECT_EQ(readExrHeader(dir + "/spp1.exr").meta.camera.spp, 1);
  EXPECT_EQ(readExrHeader(dir + "/spp4.exr").meta.camera.spp, 4);
  // The intrinsics too: the flag's focal lengths, the file's pose.
  ASSERT_EQ(runCommand(r + "--intrinsics 20,21,16,12 --out " + dir + "/k.exr", &log), 0) << log;
  InputCamera wide = kLeft;
  wide.params = {20, 21, 16, 12};
  expectRenderedBy(dir + "/k.exr", wide);
}

// ---- job files ----

std::string sphereScene() { return R"("scene": {"meshes": [{"path": "procedural:sphere"}]})"; }

TEST(CameraFilesCliJob, CamerasFromAFileWithTheImagePlaceholder) {
  const std::string dir = test::scratchDir();
  colmapModel(dir + "/model");
  // "from" is relative to the job file, as mesh paths are; run from elsewhere.
  test::writeFile(dir + "/job.json", "{" + sphereScene() + R"(,
    "cameras": {"from": "model", "images": ["left/0001.jpg", "top.png"]},
    "aovs": "depth,position", "output": "out/{image}.exr"})");
  std::string log;
  ASSERT_EQ(runCommand("cd / && " + apertureBinary() + " batch --quiet " + dir + "/job.json", &log),
            0)
      << log;
  expectRenderedBy(dir + "/out/left/0001.exr", kLeft);  // the file's size, not 960x540
  expectRenderedBy(dir + "/out/top.exr", kTop);
  EXPECT_FALSE(fs::exists(dir + "/out/right"));
  expectSidecarOf(dir + "/out/left/0001.exr", kLeft);  // "camera_files" is on by default here
  expectSidecarOf(dir + "/out/top.exr", kTop);
  const CameraFile sparse = readCameraFile(dir + "/out/sparse");
  ASSERT_EQ(sparse.images.size(), 2u);
  EXPECT_EQ(sparse.images[0].name, "left/0001.exr");
  EXPECT_EQ(sparse.images[1].name, "top.exr");
}

TEST(CameraFilesCliJob, CameraFilesFalseWritesNoSidecarsAndNoModel) {
  const std::string dir = test::scratchDir();
  colmapModel(dir + "/model");
  test::writeFile(dir + "/job.json", "{" + sphereScene() + R"(,
    "cameras": {"from": "model", "images": ["top.png"]}, "camera_files": false,
    "aovs": "depth,position", "output": "out/{image}.exr"})");
  std::string log;
  ASSERT_EQ(runCommand(apertureBinary() + " batch --quiet " + dir + "/job.json", &log), 0) << log;
  expectRenderedBy(dir + "/out/top.exr", kTop);
  EXPECT_FALSE(test::fileExists(dir + "/out/top.camera.json"));
  EXPECT_FALSE(fs::exists(dir + "/out/sparse"));
}

TEST(CameraFilesCliJob, ImagePlaceholderNeedsCamerasFromAFile) {
  const std::string dir = test::scratchDir();
  test::writeFile(dir + "/job.json", "{" + sphereScene() + R"(,
    "cameras": [{"name": "a", "eye": [0, 0, 5], "at": [0, 0, 0]}], "size": [8, 8],
    "output": "out/{image}.exr"})");
  expectRefused(apertureBinary() + " batch --quiet " + dir + "/job.json",
                {"job.json", "{image} needs cameras from a file"}, dir);
  // An unknown image in "images" names the JSON path and the closest name.
  test::writeFile(dir + "/job2.json", "{" + sphereScene() + R"(,
    "cameras": {"from": "model", "images": ["top.jpg"]}, "output": "out/{image}.exr"})");
  colmapModel(dir + "/model");
  expectRefused(apertureBinary() + " batch --quiet " + dir + "/job2.json",
                {"cameras.images", "'top.jpg'", "did you mean 'top.png'"}, dir);
}

// ---- unsupported models ----

// A model COLMAP does not have (Kalibr's name for OpenCV's fisheye).
TEST(CameraFilesCliErrors, AnUnsupportedModelIsNamed) {
  const std::string dir = test::scratchDir(), model = dir + "/kb";
  fs::create_directories(model);
  test::writeFile(model + "/cameras.txt", "1 KANNALA_BRANDT 32 24 40 40 16 12 0.9\n");
  test::writeFile(model + "/images.txt", "1 1 0 0 0 0 0 5 1 a.png\n\n");
  expectRefused(apertureBinary() + " render --quiet --mesh procedural:sphere --cameras " + model +
                    " --out " + dir + "/x.exr",
                {"KANNALA_BRANDT", "cameras.txt"}, dir);
  expectRefused(batchOneLine(model, dir + "/out"), {"KANNALA_BRANDT", "cameras.txt"}, dir);
  expectRefused(apertureBinary() + " camera --describe --cameras " + model, {"KANNALA_BRANDT"},
                dir);
}

// ---- EXR headers ----

/// The header as OpenEXR reads it.
Imf::Header exrHeader(const std::string& path) {
  Imf::InputFile file(path.c_str());
  return file.header();
}

TEST(CameraFilesCliExr, ADistortedRenderRecordsItsLensAndHasNoWorldToNdc) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  const std::string exr = dir + "/r.exr";
  std::string log;
  ASSERT_EQ(runCommand(apertureBinary() + " render --quiet --mesh " + kSphere + " --cameras " +
                           model + " --image right/0001.jpg --aov depth --out " + exr,
                       &log),
            0)
      << log;
  // Through aperture's reader...
  const ExrHeader h = readExrHeader(exr);
  ASSERT_TRUE(h.meta.camera.lens.has_value());
  const LensProjection& lens = *h.meta.camera.lens;
  EXPECT_EQ(lens.model, "OPENCV");
  EXPECT_EQ(lens.pixelCentre, "half-integer");
  EXPECT_EQ(lens.paramNames,
            (std::vector<std::string>{"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"}));
  EXPECT_EQ(lens.params, kRight.params);
  EXPECT_FALSE(h.meta.camera.ndcFromWorld.has_value());
  // ... and through OpenEXR's, attribute by attribute.
  const Imf::Header header = exrHeader(exr);
  const auto* lensModel = header.findTypedAttribute<Imf::StringAttribute>("aperture.lens.model");
  ASSERT_NE(lensModel, nullptr);
  EXPECT_EQ(lensModel->value(), "OPENCV");
  const auto* names = header.findTypedAttribute<Imf::StringAttribute>("aperture.lens.paramNames");
  ASSERT_NE(names, nullptr);
  EXPECT_EQ(names->value(), "fx fy cx cy k1 k2 p1 p2");
  const char* paramNames[] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"};
  for (size_t k = 0; k < 8; ++k) {
    const auto* v = header.findTypedAttribute<Imf::DoubleAttribute>(std::string("aperture.lens.") +
                                                                    paramNames[k]);
    ASSERT_NE(v, nullptr) << paramNames[k];
    EXPECT_EQ(v->value(), kRight.params[k]) << paramNames[k];
  }
  const auto* region =
      header.findTypedAttribute<Imf::StringAttribute>("aperture.camera.valid_region");
  ASSERT_NE(region, nullptr);
  EXPECT_EQ(region->value().rfind("r < 1.054 ", 0), 0u) << region->value();  // 1/√0.9
  EXPECT_FALSE(Imf::hasWorldToNDC(header)) << "a distorted lens is not a projective map";
  EXPECT_EQ(header.findTypedAttribute<Imf::M44dAttribute>("aperture.worldToNDC"), nullptr);
  // worldToCamera is OpenEXR's camera space (x right, y up, z forward; row vectors): the
  // input's OpenCV axes with y flipped. The centre goes to 0, the OpenCV axes (rows of R) to
  // (1, 0, 0), (0, −1, 0), (0, 0, 1).
  ASSERT_TRUE(Imf::hasWorldToCamera(header));
  const auto* w2c = header.findTypedAttribute<Imf::M44dAttribute>("aperture.worldToCamera");
  ASSERT_NE(w2c, nullptr);
  const Imath::V3d c(kRight.centre[0], kRight.centre[1], kRight.centre[2]);
  Imath::V3d q;
  w2c->value().multVecMatrix(c, q);
  EXPECT_NEAR(q.length(), 0, 1e-12);
  const Imath::V3d expected[3] = {{1, 0, 0}, {0, -1, 0}, {0, 0, 1}};
  for (size_t r = 0; r < 3; ++r) {
    const Imath::V3d axis(kRight.R[r][0], kRight.R[r][1], kRight.R[r][2]);
    w2c->value().multVecMatrix(c + axis, q);
    EXPECT_NEAR((q - expected[r]).length(), 0, 1e-12) << "OpenCV axis " << r;
  }
}

TEST(CameraFilesCliExr, APinholeRenderHasAWorldToNdcThatLandsOnPixelCentres) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  const std::string exr = dir + "/l.exr";
  std::string log;
  ASSERT_EQ(runCommand(apertureBinary() + " render --quiet --mesh " + kSphere + " --cameras " +
                           model + " --image left/0001.jpg --aov depth,position --out " + exr,
                       &log),
            0)
      << log;
  const Imf::Header header = exrHeader(exr);
  ASSERT_TRUE(Imf::hasWorldToNDC(header));
  const auto* ndc = header.findTypedAttribute<Imf::M44dAttribute>("aperture.worldToNDC");
  ASSERT_NE(ndc, nullptr);
  const auto* lensModel = header.findTypedAttribute<Imf::StringAttribute>("aperture.lens.model");
  ASSERT_NE(lensModel, nullptr);
  EXPECT_EQ(lensModel->value(), "PINHOLE");
  // OpenEXR's NDC: (0, 0) top-left, (1, 1) bottom-right of the display window, so
  // NDC · (W, H) is pixel (i, j)'s centre (j + ½, i + ½).
  const Framebuffer fb = readExr(exr);
  double worst = 0, worstAtIntegers = 0;
  const int hits = test::forEachHit(fb, [&](int i, int j, const Imath::V3d& p, double, double) {
    Imath::V3d n;
    ndc->value().multVecMatrix(p, n);
    const double x = n.x * fb.width, y = n.y * fb.height;
    worst = std::max(worst, std::hypot(x - (j + 0.5), y - (i + 0.5)));
    worstAtIntegers = std::max(worstAtIntegers, std::hypot(x - j, y - i));
  });
  EXPECT_GT(hits, fb.width * fb.height / 10);
  EXPECT_LT(worst, kMaxPixelError);
  EXPECT_GT(worstAtIntegers, 0.4) << "a half-pixel slip must be caught";
}

// ---- camera --describe ----

TEST(CameraFilesCliDescribe, ADistortedCalibratedCameraPrintsItsValidRegion) {
  const std::string dir = test::scratchDir(), model = colmapModel(dir + "/model");
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " camera --describe --cameras " + model +
                           " --image right/0001.jpg",
                       &out),
            0)
      << out;
  // ρ(r) = r(1 + k1 r²) folds where ρ' = 1 + 3 k1 r² = 0: r = 1/√0.9 = 1.054, ρ there = 2r/3
  // = 0.7027, atan(r) = 46.5° off-axis.
  const double r = 1 / std::sqrt(0.9);
  char expected[96];
  std::snprintf(expected, sizeof expected, "r < %.4g (distorted %.4g, %.1f° off-axis)", r,
                2 * r / 3, std::atan(r) * 180 / kPi);
  EXPECT_NE(out.find(expected), std::string::npos) << expected << " in\n" << out;
  EXPECT_NE(out.find("OPENCV"), std::string::npos) << out;
  // A distorted lens has no worldToNDC, and it is not a panorama.
  EXPECT_NE(out.find("worldToNDC: none (a lens with distortion"), std::string::npos) << out;
  EXPECT_EQ(out.find("panorama"), std::string::npos) << out;
  // Every pixel of this sensor lies inside the region (its corner is at r ≈ 0.55).
  EXPECT_NE(out.find("768 of 768"), std::string::npos) << out;
}

}  // namespace
}  // namespace aperture
