// Calibrated cameras end to end on a real mesh (the Stanford bunny of ../shared/meshes): camera
// files written by the project's writers (or by hand, as a user would), read back with
// readCameraFile, and rendered through the frame loop.
//  - every COLMAP model: the hit point P of every pixel re-projects through the lens onto the
//    pixel's centre; COLMAP text and binary give the same image bit for bit;
//  - pixels past a lens's fold are misses, pixels just inside it hit;
//  - transforms.json (nerfstudio, original NeRF) and OpenCV JSON / YAML: P re-projects onto
//    the pixel centre through this file's own reading of each format's conventions, and a
//    half-pixel slip or a y flip in that reading is caught;
//  - a lecture perspective camera exported to each format and imported renders as itself.
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
#include "tests/support.h"

namespace aperture {
namespace {

using test::apertureBinary;
using test::differingAovs;
using test::runCommand;
using test::scratchDir;
using test::writeFile;

constexpr AovMask kAllAovs =
    kAovColor | kAovDepth | kAovDistance | kAovNormal | kAovPosition | kAovPrimId | kAovGeomId;
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- the scene ----

/// The bunny, loaded and built once for the whole file (members destroyed in reverse order).
struct Bunny {
  Mesh mesh;
  Device device;
  std::unique_ptr<Scene> scene;
};

const Scene& bunnyScene(const std::string& path) {
  static std::unique_ptr<Bunny> bunny;
  if (!bunny) {
    bunny = std::make_unique<Bunny>();
    bunny->mesh = loadMesh(path);
    bunny->scene = std::make_unique<Scene>(bunny->device, std::vector<const Mesh*>{&bunny->mesh});
  }
  return *bunny->scene;
}

#define REQUIRE_BUNNY(scene)                                           \
  APERTURE_REQUIRE_SHARED_MESH(bunnyPath_, "stanford/bun_zipper.ply"); \
  const Scene& scene = bunnyScene(bunnyPath_)

/// Every AOV of the camera `p` on `scene`, traced `packetWidth` rays at a time. Named apart
/// from test::render, which files sharing this one's unity batch call with an AovMask.
Framebuffer renderAllAovs(const Scene& scene, const CameraParams& p, int packetWidth = 16) {
  const std::unique_ptr<Camera> camera = makeCamera(p, scene.renderOrigin());
  RenderSettings settings;
  settings.packetWidth = packetWidth;
  Framebuffer fb(p.width, p.height, kAllAovs);
  renderImage(scene, *camera, settings, fb);
  return fb;
}

size_t hitCount(const Framebuffer& fb) {
  return size_t(std::count_if(fb.primId.begin(), fb.primId.end(),
                              [](uint32_t id) { return id != kInvalidId; }));
}

glm::dvec3 positionAt(const Framebuffer& fb, size_t k) {
  return {fb.position[3 * k], fb.position[3 * k + 1], fb.position[3 * k + 2]};
}

// ---- poses, written out here from eye / at / up ----

/// The lecture frame: W = −view, U = up × W, V = W × U (all unit).
struct Frame {
  glm::dvec3 e, u, v, w;
};
Frame frameOf(const glm::dvec3& eye, const glm::dvec3& at, const glm::dvec3& up) {
  Frame f;
  f.e = eye;
  f.w = glm::normalize(eye - at);
  f.u = glm::normalize(glm::cross(up, f.w));
  f.v = glm::cross(f.w, f.u);
  return f;
}

/// World-to-camera in OpenCV axes (rows U, −V, −W; t = −R·e), GLM m[column][row].
glm::dmat4 cvCameraFromWorldOfFrame(const Frame& f) {
  const glm::dvec3 rows[3] = {f.u, -f.v, -f.w};
  glm::dmat4 m(1.0);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[c][r] = rows[r][c];
    m[3][r] = -glm::dot(rows[r], f.e);
  }
  return m;
}

// Reference views of the bunny (its README): from the front, a little rolled so that no
// rotation entry is zero; fisheyes closer, so that the bunny fills more of their wide view.
const glm::dvec3 kBunnyAt(-0.017, 0.11, 0.0);
const glm::dvec3 kRolledUp(0.15, 1.0, 0.05);
Frame perspectiveView() { return frameOf({-0.02, 0.11, 0.35}, kBunnyAt, kRolledUp); }
Frame fisheyeView() { return frameOf({0.01, 0.12, 0.17}, kBunnyAt, kRolledUp); }

// ---- re-projection ----

/// Distances between where hit points re-project and the centres of their pixels.
struct Reprojection {
  size_t hits = 0;
  size_t unprojected = 0;  ///< hits whose P the projection gives no position (counted as +inf)
  double p99 = kInf, max = kInf;
  std::string text() const {
    char s[160];
    std::snprintf(s, sizeof s, "%zu hits, p99 %.3g px, max %.3g px, %zu without a projection", hits,
                  p99, max, unprojected);
    return s;
  }
};

/// `project` maps a world point to aperture's raster (pixel (i, j) centre at (j + ½, i + ½)).
using Projection = std::function<std::optional<glm::dvec2>(const glm::dvec3&)>;

Reprojection reprojection(const Framebuffer& fb, const Projection& project) {
  std::vector<double> errors;
  Reprojection r;
  for (int i = 0; i < fb.height; ++i)
    for (int j = 0; j < fb.width; ++j) {
      const size_t k = size_t(i) * size_t(fb.width) + size_t(j);
      if (fb.primId[k] == kInvalidId) continue;
      const std::optional<glm::dvec2> x = project(positionAt(fb, k));
      r.unprojected += !x;
      errors.push_back(x ? glm::length(*x - glm::dvec2(j + 0.5, i + 0.5)) : kInf);
    }
  r.hits = errors.size();
  if (errors.empty()) return r;
  std::sort(errors.begin(), errors.end());
  r.p99 = errors[size_t(std::ceil(0.99 * double(errors.size()))) - 1];
  r.max = errors.back();
  return r;
}

Projection projectionOf(const CameraBase& camera) {
  return [&camera](const glm::dvec3& p) { return camera.project(p); };
}

// ---- 1. every COLMAP model, text and binary ----

struct ModelCase {
  LensModelId model;
  std::vector<double> params;  ///< COLMAP's order
};

constexpr int kW = 160, kH = 120;

// Realistic, clearly non-zero distortion. The fisheyes are wide enough that the image corners
// (100 px from the centre) lie outside the valid region: θ = π for OPENCV_FISHEYE, whose
// ρ(θ) = θ(1 − 0.05θ² + 0.002θ⁴) has no fold (ρ(π) = 2.20, 88 px at f = 40); the fold of
// SIMPLE_RADIAL_FISHEYE at θ = 2.357 (ρ = 1.571, 71 px), of RADIAL_FISHEYE at θ = 2.54
// (ρ = 1.84, 92 px) and of THIN_PRISM_FISHEYE at θ = 2.62 (ρ = 1.66, 70 px).
std::vector<ModelCase> modelCases() {
  return {
      {LensModelId::SimplePinhole, {150, 81.3, 58.9}},
      {LensModelId::Pinhole, {150, 152.5, 78.6, 61.2}},
      {LensModelId::SimpleRadial, {150, 81.3, 58.9, -0.15}},
      {LensModelId::Radial, {150, 81.3, 58.9, -0.2, 0.05}},
      {LensModelId::OpenCV, {150, 151, 81.3, 58.9, -0.2, 0.03, 1e-3, -5e-4}},
      {LensModelId::OpenCVFisheye, {40, 40.5, 80.7, 59.6, -0.05, 0.002, 0, 0}},
      {LensModelId::FullOpenCV,
       {150, 151, 81.3, 58.9, -0.2, 0.03, 1e-3, -5e-4, 0.01, 0.05, 0.002, 0.01}},
      {LensModelId::SimpleRadialFisheye, {45, 80.4, 60.3, -0.06}},
      {LensModelId::RadialFisheye, {50, 79.8, 60.1, -0.03, -0.002}},
      {LensModelId::ThinPrismFisheye,
       {42, 42.5, 80.2, 59.7, -0.06, 0.001, 1e-3, -1e-3, 0, 0, 1e-3, -5e-4}},
  };
}

CameraFile everyModelFile() {
  CameraFile file;
  for (const ModelCase& c : modelCases()) {
    const Lens lens(c.model, c.params);
    const bool fisheye = lens.info().fisheye;
    file.sensors.push_back({kW, kH, lens, PixelCentre::HalfInteger});
    file.sensorIds.push_back(std::to_string(file.sensors.size()));
    file.images.push_back({std::string("bunny_") + lens.info().name + ".png",
                           int(file.sensors.size() - 1),
                           cvCameraFromWorldOfFrame(fisheye ? fisheyeView() : perspectiveView())});
  }
  return file;
}

CameraParams paramsOfImage(const CameraFile& file, size_t k) {
  const CalibratedImage& im = file.images.at(k);
  return calibratedCameraParams(file.sensors.at(size_t(im.sensor)), im.cvCameraFromWorld);
}

TEST(CalibratedRenderColmap, EveryModelReprojectsOntoPixelCentresAndTextEqualsBinary) {
  REQUIRE_BUNNY(scene);
  const std::string dir = scratchDir();
  const CameraFile written = everyModelFile();
  writeColmapText(written, dir + "/text");
  writeColmapBinary(written, dir + "/binary");
  const CameraFile text = readCameraFile(dir + "/text");
  const CameraFile binary = readCameraFile(dir + "/binary");
  EXPECT_EQ(text.format, CameraFileFormat::ColmapText);
  EXPECT_EQ(binary.format, CameraFileFormat::ColmapBinary);
  ASSERT_EQ(text.images.size(), written.images.size());
  ASSERT_EQ(binary.images.size(), written.images.size());
  for (size_t k = 0; k < written.images.size(); ++k) {
    const CalibratedSensor& sensor = written.sensors[k];
    const std::string name = sensor.lens.info().name;
    SCOPED_TRACE(name);
    ASSERT_EQ(text.images[k].name, written.images[k].name);
    ASSERT_TRUE(text.sensors[size_t(text.images[k].sensor)] == sensor);
    const CameraParams p = paramsOfImage(text, k);
    const Framebuffer fb = renderAllAovs(scene, p);
    EXPECT_EQ(differingAovs(fb, renderAllAovs(scene, paramsOfImage(binary, k))), "")
        << "COLMAP text and binary must render the same image";

    const std::unique_ptr<CameraBase> camera = makeCameraModel(p, glm::dvec3(0.0));
    const Reprojection r = reprojection(fb, projectionOf(*camera));
    std::printf("[ CalibratedRender ] %-21s %s\n", name.c_str(), r.text().c_str());
    EXPECT_GE(r.hits, 500u) << "the bunny must fill part of the view";
    EXPECT_LE(r.p99, 1e-3) << r.text();

    // A pixel the lens gives no ray (an independent count: the forward model cannot reach
    // it) is a miss; the fisheyes have such pixels in their corners.
    size_t noRay = 0;
    for (int i = 0; i < kH; ++i)
      for (int j = 0; j < kW; ++j)
        if (!sensor.lens.unproject({j + 0.5, i + 0.5})) {
          ++noRay;
          EXPECT_EQ(fb.primId[size_t(i) * kW + size_t(j)], kInvalidId) << i << "," << j;
        }
    if (sensor.lens.info().fisheye) {
      EXPECT_GT(noRay, 0u) << "the corners lie outside the valid region";
      EXPECT_TRUE(sensor.lens.validRegion().bounded());
    }
  }
}

// ---- 2. pixels past a fold ----

// SIMPLE_RADIAL with k = −0.5: ρ(r) = r(1 − r²/2) has its fold where ρ' = 1 − 1.5r² = 0, at
// r* = √(2/3), ρ* = (2/3)·r* = 0.5443. At f = 160 the fold is a circle of 87.1 px about the
// image centre: the corners (99 px away) lie beyond it, the middle of each side inside.
// The camera sits inside the bunny's body, so every ray the lens gives meets the surface.
TEST(CalibratedRenderFold, PixelsPastTheFoldAreMissesAndPixelsJustInsideHit) {
  REQUIRE_BUNNY(scene);
  const double f = 160, cx = 80, cy = 60, k = -0.5;
  const double foldRho = (2.0 / 3.0) * std::sqrt(2.0 / 3.0);
  CalibratedSensor sensor{kW, kH, Lens(LensModelId::SimpleRadial, {f, cx, cy, k}),
                          PixelCentre::HalfInteger};
  const Frame inside = frameOf({-0.025, 0.09, 0.0}, {-0.1, 0.09, -0.02}, {0, 1, 0});
  const CameraParams p = calibratedCameraParams(sensor, cvCameraFromWorldOfFrame(inside));
  const Framebuffer reference = renderAllAovs(scene, p);
  for (int width : {1, 4, 8, 16}) {
    SCOPED_TRACE(width);
    const Framebuffer fb = width == 16 ? reference : renderAllAovs(scene, p, width);
    size_t beyond = 0, rim = 0;
    for (int i = 0; i < kH; ++i)
      for (int j = 0; j < kW; ++j) {
        const size_t px = size_t(i) * kW + size_t(j);
        const double rho = std::hypot(j + 0.5 - cx, i + 0.5 - cy) / f;
        if (rho > foldRho * (1 + 1e-9)) {
          ++beyond;
          EXPECT_EQ(fb.depth[px], float(kInf)) << i << "," << j;
          EXPECT_EQ(fb.distance[px], float(kInf)) << i << "," << j;
          EXPECT_EQ(fb.primId[px], kInvalidId) << i << "," << j;
          EXPECT_EQ(fb.geomId[px], kInvalidId) << i << "," << j;
          EXPECT_EQ(fb.rgba[4 * px + 3], 0.0f) << "no coverage at " << i << "," << j;
        } else if (rho < foldRho * (1 - 1e-9) && rho > foldRho - 2 / f) {
          ++rim;  // within two pixels inside the fold
          EXPECT_NE(fb.primId[px], kInvalidId) << i << "," << j;
          EXPECT_TRUE(std::isfinite(fb.depth[px])) << i << "," << j;
        }
      }
    EXPECT_GT(beyond, 600u);
    EXPECT_GT(rim, 200u);
    EXPECT_EQ(differingAovs(fb, reference), "") << "every packet width renders the same";
  }
}

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

// ---- 4. a lecture camera exported and imported renders as itself ----

/// How two renders of the same view differ: pixels with any AOV's bits different, pixels
/// whose hit triangle changed, and the largest relative difference of depth where both hit.
struct RenderDifference {
  size_t pixels = 0, triangles = 0, hitChanged = 0;
  double maxDepthRel = 0;
  std::string aovs;
  std::string text() const {
    char s[200];
    std::snprintf(s, sizeof s,
                  "%zu pixels differ (AOVs: %s), %zu on another triangle, %zu hit/miss "
                  "changed, depth up to %.3g relative",
                  pixels, aovs.empty() ? "none" : aovs.c_str(), triangles, hitChanged, maxDepthRel);
    return s;
  }
};

bool samePixel(const Framebuffer& a, const Framebuffer& b, size_t k) {
  const auto same = [](const auto& x, const auto& y, size_t from, size_t n) {
    return std::memcmp(&x[from], &y[from], n * sizeof(x[0])) == 0;
  };
  return same(a.rgba, b.rgba, 4 * k, 4) && same(a.depth, b.depth, k, 1) &&
         same(a.distance, b.distance, k, 1) && same(a.normal, b.normal, 3 * k, 3) &&
         same(a.position, b.position, 3 * k, 3) && same(a.primId, b.primId, k, 1) &&
         same(a.geomId, b.geomId, k, 1);
}

RenderDifference differenceOf(const Framebuffer& a, const Framebuffer& b) {
  RenderDifference d;
  d.aovs = differingAovs(a, b);
  if (a.width != b.width || a.height != b.height) {
    d.pixels = std::max(a.pixelCount(), b.pixelCount());
    return d;
  }
  for (size_t k = 0; k < a.pixelCount(); ++k) {
    if (samePixel(a, b, k)) continue;
    ++d.pixels;
    const bool hitA = a.primId[k] != kInvalidId, hitB = b.primId[k] != kInvalidId;
    d.hitChanged += hitA != hitB;
    d.triangles += hitA && hitB && a.primId[k] != b.primId[k];
    if (hitA && hitB)
      d.maxDepthRel =
          std::max(d.maxDepthRel, std::abs(double(a.depth[k]) - b.depth[k]) / double(a.depth[k]));
  }
  return d;
}

struct Writer {
  const char* name;
  std::function<void(const CameraFile&, const std::string&)> write;
  const char* file;  ///< what readCameraFile is given, below the folder written into
};

std::vector<Writer> writers() {
  return {{"COLMAP text", writeColmapText, ""},
          {"COLMAP binary", writeColmapBinary, ""},
          {"nerfstudio", writeNerfstudioJson, "transforms.json"},
          {"OpenCV JSON", writeOpenCVJson, "calib.json"}};
}

std::vector<CameraParams> lectureCameras() {
  std::vector<CameraParams> cams;
  const struct {
    int w, h;
    double fov;
    glm::dvec2 shift;
  } views[] = {{160, 120, 30, {0, 0}}, {160, 120, 30, {0.15, -0.1}},
               {161, 97, 35, {0, 0}},  {161, 97, 35, {-0.2, 0.125}},
               {96, 144, 25, {0, 0}},  {96, 144, 25, {0.05, 0.3}}};
  for (const auto& v : views) {
    CameraParams p;
    p.type = "perspective";
    p.width = v.w;
    p.height = v.h;
    p.eye = {-0.02, 0.11, 0.35};
    p.at = kBunnyAt;
    p.up = kRolledUp;
    p.fovDeg = v.fov;
    p.shift = v.shift;
    cams.push_back(p);
  }
  return cams;
}

// The calibrated camera computes a ray as R·unproject(pixel), the lecture camera as
// u·U + v·V − d·W, and the file's numbers differ from the lecture's in the last bits (COLMAP's
// quaternion changes R; e = −Rᵀt after t = −R·e; W / fx and the principal point's shift need
// not give back vw and the lecture's shift): the double directions differ by up to ~5e-16 in
// most pixels. Rounding to float, what Embree traces, absorbs that for every pixel of these
// views, so the renders are bit-identical. (Over random views a float direction differs in
// about one ray in 10⁷, mostly where a component is near 0: bit-identity is checked here for
// these views, not promised for every view.)
TEST(CalibratedRenderRoundTrip, LectureCameraThroughEveryWriterRendersAsItself) {
  REQUIRE_BUNNY(scene);
  const std::string dir = scratchDir();
  int n = 0;
  for (const CameraParams& lecture : lectureCameras()) {
    const std::string label =
        cat(lecture.width, "x", lecture.height, " shift ", lecture.shift.x, ",", lecture.shift.y);
    const std::optional<CalibratedView> view = calibratedViewOf(lecture);
    ASSERT_TRUE(view) << label;
    EXPECT_EQ(view->sensor.lens.model(), LensModelId::Pinhole);
    const Framebuffer reference = renderAllAovs(scene, lecture);
    EXPECT_GE(hitCount(reference), 500u) << label;
    CameraFile file;
    file.sensors = {view->sensor};
    file.images = {{"view.png", 0, view->cvCameraFromWorld}};
    for (const Writer& w : writers()) {
      const std::string out = cat(dir, "/", n++);
      const std::string path = *w.file ? out + "/" + w.file : out;
      w.write(file, path);
      const CameraFile back = readCameraFile(path);
      ASSERT_EQ(back.images.size(), 1u);
      const Framebuffer fb = renderAllAovs(scene, paramsOfImage(back, 0));
      const RenderDifference d = differenceOf(reference, fb);
      std::printf("[ CalibratedRender ] %-14s %-22s %s\n", w.name, label.c_str(), d.text().c_str());
      EXPECT_EQ(d.pixels, 0u) << w.name << " " << label << ": " << d.text();
    }
    // The comparison sees a principal point half a pixel off.
    CalibratedView slipped = *view;
    std::vector<double> q = slipped.sensor.lens.params();
    q[2] += 0.5;
    slipped.sensor.lens = Lens(LensModelId::Pinhole, q);
    const RenderDifference d = differenceOf(
        reference,
        renderAllAovs(scene, calibratedCameraParams(slipped.sensor, slipped.cvCameraFromWorld)));
    EXPECT_GT(d.pixels, hitCount(reference) / 2) << "a half-pixel slip: " << d.text();
  }
}

// --max-memory counts the direction tables of distorted lenses: a table's bytes are known
// from the sensor's size alone, each sensor counts once, and the cache bounds the rest.
TEST(DirectionTableMemory, BytesForIsWhatATableHolds) {
  for (const glm::ivec2 size : {glm::ivec2(64, 48), glm::ivec2(37, 23), glm::ivec2(1, 1)}) {
    CalibratedSensor s;
    s.width = size.x, s.height = size.y;
    s.lens = Lens(LensModelId::OpenCV, {50, 50, size.x / 2.0, size.y / 2.0, -0.1, 0.01, 0, 0});
    EXPECT_EQ(DirectionTable::bytesFor(size.x, size.y), DirectionTable(s).bytes())
        << size.x << "x" << size.y;
  }
}

TEST(DirectionTableMemory, PeakCountsEachSensorOnceUpToTheCacheAndTheLargest) {
  auto sensor = [](int width, int height, double k1) {
    CalibratedSensor s;
    s.width = width, s.height = height;
    s.lens = Lens(LensModelId::SimpleRadial, {1000, width / 2.0, height / 2.0, k1});
    return s;
  };
  const size_t hd = DirectionTable::bytesFor(1920, 1080);
  // The same sensor twice counts once; another lens or size counts again.
  EXPECT_EQ(DirectionTable::peakBytes({sensor(1920, 1080, -0.1), sensor(1920, 1080, -0.1)}), hd);
  EXPECT_EQ(DirectionTable::peakBytes({sensor(1920, 1080, -0.1), sensor(1920, 1080, -0.2)}),
            2 * hd);
  // Far more sensors than the cache keeps: its bound plus the largest, computed beside it.
  std::vector<CalibratedSensor> many;
  for (int k = 0; k < 60; ++k) many.push_back(sensor(1920, 1080, -0.1 - 0.001 * k));
  many.push_back(sensor(4000, 3000, -0.1));
  EXPECT_EQ(DirectionTable::peakBytes(many),
            DirectionTable::kCacheBytes + DirectionTable::bytesFor(4000, 3000));
  EXPECT_EQ(DirectionTable::peakBytes({}), 0u);
}

// The render command refuses a distorted 12 Mpx camera whose table (313 MB) does not fit the
// limit, naming the tables; the same camera without distortion (no table) renders.
TEST(DirectionTableMemory, MaxMemoryRefusesATableThatDoesNotFit) {
  const std::string dir = scratchDir();
  const std::string camera =
      " --quiet --mesh procedural:sphere --size 4000,3000 --aov depth --eye 0,0,5 --at 0,0,0"
      " --intrinsics 3000,3000,2000,1500 --max-memory 200M --out " +
      dir + "/out.exr";
  std::string out;
  EXPECT_EQ(runCommand(apertureBinary() + " render" + camera +
                           " --lens-model OPENCV --distortion -0.1,0.01,0,0",
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("lens direction tables 313.5 MB"), std::string::npos) << out;
  EXPECT_NE(out.find("--max-memory 200M"), std::string::npos) << out;
  EXPECT_EQ(runCommand(apertureBinary() + " render" + camera + " --lens-model PINHOLE", &out), 0)
      << out;
}

}  // namespace
}  // namespace aperture
