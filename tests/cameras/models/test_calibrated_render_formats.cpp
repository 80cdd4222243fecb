// Calibrated cameras from files written by hand, as a user would, rendered on a real mesh (the
// Stanford bunny of ../shared/meshes): transforms.json (nerfstudio, original NeRF) and OpenCV
// JSON / YAML. P re-projects onto the pixel centre through this file's own reading of each
// format's conventions, and a half-pixel slip or a y flip in that reading is caught.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "cameras/lenses/direction_table.h"
#include "cameras/models/base.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/camera_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::apertureBinary;
using test::bunnyScene;
using test::differingAovs;
using test::Frame;
using test::frameOf;
using test::kBunnyAt;
using test::kRolledUp;
using test::paramsOfImage;
using test::perspectiveView;
using test::positionAt;
using test::Projection;
using test::renderAllAovs;
using test::reprojection;
using test::Reprojection;
using test::runCommand;
using test::scratchDir;
using test::writeFile;

// ---- 3. transforms.json and OpenCV files, checked by this file's reading of them ----

/// Text of a double that reads back to the same bits.
std::string num(double x) {
  char s[40];
  std::snprintf(s, sizeof s, "%.17g", x);
  return s;
}

/// The camera-to-world matrix in OpenGL axes (columns U, V, W, e) as JSON rows.
std::string worldFromGlCameraJson(const Frame& f) {
  std::ostringstream s;
  s << "[";
  for (int r = 0; r < 3; ++r)
    s << "[" << num(f.u[r]) << ", " << num(f.v[r]) << ", " << num(f.w[r]) << ", " << num(f.e[r])
      << "], ";
  s << "[0, 0, 0, 1]]";
  return s.str();
}

/// OpenCV's distortion (k1, k2, p1, p2, k3) of normalised image coordinates (x/z, y/z), as
/// OpenCV's documentation of projectPoints writes it.
glm::dvec2 openCVDistort(const double d[5], double a, double b) {
  const double r2 = a * a + b * b;
  const double radial = 1 + d[0] * r2 + d[1] * r2 * r2 + d[4] * r2 * r2 * r2;
  return {a * radial + 2 * d[2] * a * b + d[3] * (r2 + 2 * a * a),
          b * radial + 2 * d[3] * a * b + d[2] * (r2 + 2 * b * b)};
}

/// What a test's reading of a format can get wrong, to show the check catches it.
enum class Slip { None, HalfPixel, FlipY };

struct PinholeIntrinsics {
  double fx, fy, cx, cy;
  double dist[5];  ///< k1, k2, p1, p2, k3
};

/// The raster position of world point p for a camera frame and intrinsics whose pixel centre
/// of pixel (i, j) is at (j, i) + centreOffset (0.5 for nerfstudio, 0 for OpenCV). Camera
/// space in OpenCV axes: x = (p − e)·U, y = −(p − e)·V, z = −(p − e)·W.
std::optional<glm::dvec2> expectedRaster(const Frame& f, const PinholeIntrinsics& k,
                                         double centreOffset, Slip slip, const glm::dvec3& p) {
  const glm::dvec3 q = p - f.e;
  const double x = glm::dot(q, f.u), z = -glm::dot(q, f.w);
  const double y = slip == Slip::FlipY ? glm::dot(q, f.v) : -glm::dot(q, f.v);
  if (!(z > 0)) return std::nullopt;
  const glm::dvec2 d = openCVDistort(k.dist, x / z, y / z);
  const glm::dvec2 pixel(k.fx * d.x + k.cx, k.fy * d.y + k.cy);
  // Raster = source pixel + (½ − centreOffset); the slip takes the other convention.
  const double toRaster = slip == Slip::HalfPixel ? centreOffset : 0.5 - centreOffset;
  return pixel + glm::dvec2(toRaster);
}

/// Renders the single image of a camera file and checks its hit points against this file's
/// own projection: within 1e-3 px at the 99th percentile, and over 0.25 px with either slip.
void expectReprojectsByOwnReading(const Scene& scene, const std::string& path, const Frame& f,
                                  const PinholeIntrinsics& k, double centreOffset,
                                  CameraFileFormat format) {
  const CameraFile file = readCameraFile(path);
  EXPECT_EQ(file.format, format);
  ASSERT_EQ(file.images.size(), 1u);
  const Framebuffer fb = renderAllAovs(scene, paramsOfImage(file, 0));
  const auto check = [&](Slip slip) {
    return reprojection(
        fb, [&](const glm::dvec3& p) { return expectedRaster(f, k, centreOffset, slip, p); });
  };
  const Reprojection right = check(Slip::None);
  std::printf("[ CalibratedRender ] %-21s %s\n", cameraFileFormatName(format),
              right.text().c_str());
  EXPECT_GE(right.hits, 500u);
  EXPECT_LE(right.p99, 1e-3) << right.text();
  const Reprojection halfPixel = check(Slip::HalfPixel), flipY = check(Slip::FlipY);
  std::printf(
      "[ CalibratedRender ] %-21s with a half-pixel slip p99 %.3g px, with a y flip %.3g px\n", "",
      halfPixel.p99, flipY.p99);
  EXPECT_GT(halfPixel.p99, 0.25) << "a half-pixel slip must be caught: " << halfPixel.text();
  EXPECT_GT(flipY.p99, 0.25) << "a y flip must be caught: " << flipY.text();
}

TEST(CalibratedRenderNerf, NerfstudioWithOpenCVDistortion) {
  REQUIRE_BUNNY(scene);
  const Frame f = perspectiveView();
  const PinholeIntrinsics k{150, 151, 81.3, 58.9, {-0.2, 0.03, 1e-3, -5e-4, 0}};
  const std::string path = scratchDir() + "/transforms.json";
  writeFile(path, "{\"camera_model\": \"OPENCV\", \"fl_x\": " + num(k.fx) + ", \"fl_y\": " +
                      num(k.fy) + ", \"cx\": " + num(k.cx) + ", \"cy\": " + num(k.cy) +
                      ", \"w\": 160, \"h\": 120, \"k1\": " + num(k.dist[0]) +
                      ", \"k2\": " + num(k.dist[1]) + ", \"p1\": " + num(k.dist[2]) +
                      ", \"p2\": " + num(k.dist[3]) +
                      ",\n \"frames\": [{\"file_path\": \"images/frame_00001.png\", "
                      "\"transform_matrix\": " +
                      worldFromGlCameraJson(f) + "}]}\n");
  expectReprojectsByOwnReading(scene, path, f, k, 0.5, CameraFileFormat::Nerfstudio);
}

TEST(CalibratedRenderNerf, OriginalNerfWithCameraAngleXOnly) {
  REQUIRE_BUNNY(scene);
  const Frame f = perspectiveView();
  // fx = fy = (w / 2) / tan(camera_angle_x / 2), principal point at the image centre.
  const double angleX = 0.9;
  const double focal = 80 / std::tan(angleX / 2);
  const PinholeIntrinsics k{focal, focal, 80, 60, {0, 0, 0, 0, 0}};
  const std::string path = scratchDir() + "/transforms_train.json";
  writeFile(path, "{\"camera_angle_x\": " + num(angleX) +
                      ", \"w\": 160, \"h\": 120,\n \"frames\": [{\"file_path\": \"./train/r_0\", "
                      "\"rotation\": 0.012566370614359171, \"transform_matrix\": " +
                      worldFromGlCameraJson(f) + "}]}\n");
  expectReprojectsByOwnReading(scene, path, f, k, 0.5, CameraFileFormat::InstantNgp);
}

/// R (rows U, −V, −W) and t = −R·e of a frame, as OpenCV writes them.
void openCVPose(const Frame& f, double R[3][3], double t[3]) {
  const glm::dvec3 rows[3] = {f.u, -f.v, -f.w};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R[r][c] = rows[r][c];
    t[r] = -glm::dot(rows[r], f.e);
  }
}

TEST(CalibratedRenderOpenCV, JsonWithFiveCoefficientsAndIntegerPixelCentres) {
  REQUIRE_BUNNY(scene);
  const Frame f = perspectiveView();
  const PinholeIntrinsics k{150, 151, 80.8, 58.4, {-0.2, 0.03, 1e-3, -5e-4, 0.01}};
  double R[3][3], t[3];
  openCVPose(f, R, t);
  std::string rows;
  for (int r = 0; r < 3; ++r)
    rows += std::string(r ? ", " : "") + "[" + num(R[r][0]) + ", " + num(R[r][1]) + ", " +
            num(R[r][2]) + "]";
  const std::string path = scratchDir() + "/calib.json";
  writeFile(path, "{\"name\": \"cam0\", \"width\": 160, \"height\": 120, \"K\": [[" + num(k.fx) +
                      ", 0, " + num(k.cx) + "], [0, " + num(k.fy) + ", " + num(k.cy) +
                      "], [0, 0, 1]], \"dist\": [" + num(k.dist[0]) + ", " + num(k.dist[1]) + ", " +
                      num(k.dist[2]) + ", " + num(k.dist[3]) + ", " + num(k.dist[4]) +
                      "], \"R\": [" + rows + "], \"t\": [" + num(t[0]) + ", " + num(t[1]) + ", " +
                      num(t[2]) + "]}\n");
  expectReprojectsByOwnReading(scene, path, f, k, 0.0, CameraFileFormat::OpenCVJson);
}

TEST(CalibratedRenderOpenCV, FileStorageYamlWithIntegerPixelCentres) {
  REQUIRE_BUNNY(scene);
  const Frame f = perspectiveView();
  const PinholeIntrinsics k{150, 150, 79.5, 59.5, {-0.2, 0.03, 1e-3, -5e-4, 0}};
  double R[3][3], t[3];
  openCVPose(f, R, t);
  std::string data;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) data += std::string(r || c ? ", " : "") + num(R[r][c]);
  const std::string path = scratchDir() + "/calib.yaml";
  writeFile(path,
            "%YAML:1.0\n---\ncam0:\n   width: 160\n   height: 120\n"
            "   K: !!opencv-matrix\n      rows: 3\n      cols: 3\n      dt: d\n"
            "      data: [ " +
                num(k.fx) + ", 0., " + num(k.cx) + ", 0., " + num(k.fy) + ", " + num(k.cy) +
                ", 0., 0., 1. ]\n"
                "   dist: !!opencv-matrix\n      rows: 1\n      cols: 4\n      dt: d\n"
                "      data: [ " +
                num(k.dist[0]) + ", " + num(k.dist[1]) + ", " + num(k.dist[2]) + ", " +
                num(k.dist[3]) +
                " ]\n"
                "   R: !!opencv-matrix\n      rows: 3\n      cols: 3\n      dt: d\n"
                "      data: [ " +
                data + " ]\n   t: [ " + num(t[0]) + ", " + num(t[1]) + ", " + num(t[2]) + " ]\n");
  expectReprojectsByOwnReading(scene, path, f, k, 0.0, CameraFileFormat::OpenCVYaml);
}

}  // namespace
}  // namespace aperture
