// A lens model is one row of the table (cameras/lens_model.h): a model aperture does not ship,
// with a distortion term none of COLMAP's models has, is registered here through the table
// alone (no other file knows it) and then renders, round-trips through the COLMAP writers and
// readers, and is refused by the formats that cannot express it.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "cameras/files/camera_file_formats.h"
#include "cameras/lenses/lens_model.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::errorOf;
using test::readFile;
using test::scratchDir;

// ρ(r) = r·(1 + k·r): an odd radial term (k·|x|·x), which no COLMAP model has (theirs are
// polynomials in r²). ρ' = 1 + 2k·r: for k < 0 the fold is at r* = −1/(2k), ρ* = r*/2.
void oddProfile(const double* k, double r, double& rho, double& drho) {
  rho = r * (1 + k[0] * r);
  drho = 1 + 2 * k[0] * r;
}
const LensFormula kOddFormula{oddProfile, nullptr, nullptr};
const LensModelId kOddId = LensModelId(1000);

class TestOnlyLensModel : public ::testing::Test {
 protected:
  void SetUp() override {
    registerLensModel({kOddId,
                       "TEST_ODD_RADIAL",
                       1000,
                       {"f", "cx", "cy", "k"},
                       false,
                       nullptr,
                       &kOddFormula,
                       {},
                       {},
                       {}});
  }
  void TearDown() override { unregisterLensModel(kOddId); }
};

constexpr int kRowW = 160, kRowH = 120;

TEST_F(TestOnlyLensModel, RendersRoundTripsThroughColmapAndIsRefusedElsewhere) {
  const double f = 60, k = -0.3;
  const CalibratedSensor sensor{kRowW, kRowH, Lens(kOddId, {f, 80, 60, k}),
                                PixelCentre::HalfInteger};
  const Lens& lens = sensor.lens;
  EXPECT_EQ(&lens.info(), &findLensModel("test_odd_radial"));
  EXPECT_EQ(findLensModelByColmapId(1000), &lens.info());
  // The valid region is the closed form's: r* = 1/0.6, ρ* = r*/2 (50 px at f = 60, so the
  // image corners, 100 px out, have no ray).
  EXPECT_NEAR(lens.validRegion().maxUndistorted, 1 / 0.6, 1e-12);
  EXPECT_NEAR(lens.validRegion().maxDistorted, 0.5 / 0.6, 1e-12);

  // Rendered from inside a sphere every ray hits: each hit's pixel centre is where the forward
  // formula takes its point, and the pixels past the fold are misses.
  Device device;
  const Mesh sphere = loadMesh("procedural:sphere?radius=10&segments=128&rings=64");
  const Scene scene(device, std::vector<const Mesh*>{&sphere});
  const CameraParams p = calibratedCameraParams(sensor, glm::dmat4(1.0));
  const std::unique_ptr<Camera> camera = makeCamera(p, scene.renderOrigin());
  Framebuffer fb(kRowW, kRowH, kAovPosition | kAovPrimId);
  renderImage(scene, *camera, RenderSettings{}, fb);
  size_t hits = 0, misses = 0;
  double worst = 0;
  for (int i = 0; i < kRowH; ++i)
    for (int j = 0; j < kRowW; ++j) {
      const size_t px = size_t(i) * kRowW + size_t(j);
      const glm::dvec2 centre(j + 0.5, i + 0.5);
      const double rho = glm::length(centre - glm::dvec2(80, 60)) / f;
      if (fb.primId[px] == kInvalidId) {
        ++misses;
        EXPECT_GE(rho, 0.5 / 0.6 * (1 - 1e-9))
            << "a miss inside the valid region at " << i << "," << j;
        continue;
      }
      ++hits;
      EXPECT_LT(rho, 0.5 / 0.6 * (1 + 1e-9)) << "a hit past the fold at " << i << "," << j;
      // The ray's direction from the eye (the origin): P itself, in OpenCV axes = world here.
      const glm::dvec3 point(fb.position[3 * px], fb.position[3 * px + 1], fb.position[3 * px + 2]);
      // The forward formula written out: u = P/z, ρ = r(1 + k r), pixel = f·ρ·u/r + c.
      const glm::dvec2 u(point.x / point.z, point.y / point.z);
      const double r = glm::length(u);
      const glm::dvec2 pixel = glm::dvec2(80, 60) + f * (1 + k * r) * u;
      worst = std::max(worst, glm::length(pixel - centre));
    }
  EXPECT_NEAR(double(hits), 3.14159265 * 50 * 50, 100) << "the disc of the fold's 50 px radius";
  EXPECT_GT(misses, 0u) << "the corners lie past the fold";
  EXPECT_LT(worst, 1e-3) << "pixels from the hit points";

  // COLMAP text and binary carry it by its name and its id, and read back the same sensor.
  const std::string dir = scratchDir();
  CameraFile file;
  file.sensors = {sensor};
  file.sensorIds = {"1"};
  file.images = {{"a.png", 0, glm::dmat4(1.0)}};
  writeColmapText(file, dir + "/text");
  writeColmapBinary(file, dir + "/binary");
  EXPECT_NE(readFile(dir + "/text/cameras.txt").find("1 TEST_ODD_RADIAL 160 120 60 80 60 -0.29"),
            std::string::npos);
  for (const char* folder : {"/text", "/binary"}) {
    const CameraFile back = readCameraFile(dir + folder);
    ASSERT_EQ(back.sensors.size(), 1u) << folder;
    EXPECT_TRUE(back.sensors[0] == sensor) << folder;
  }

  // OpenCV and nerfstudio have no spelling of it: their writers refuse it by name.
  EXPECT_FALSE(camera_files::openCVLens(lens));
  const std::string opencv = errorOf([&] { writeOpenCVJson(file, dir + "/cv.json"); });
  EXPECT_NE(opencv.find("TEST_ODD_RADIAL"), std::string::npos) << opencv;
  const std::string nerf = errorOf([&] { writeNerfstudioJson(file, dir + "/ns.json"); });
  EXPECT_NE(nerf.find("TEST_ODD_RADIAL has no nerfstudio camera_model"), std::string::npos) << nerf;
}

TEST(LensRows, RegistrationRefusesATakenNameOrIdAndARowWithoutOneFormula) {
  const LensFormula formula{oddProfile, nullptr, nullptr};
  const auto row = [&](LensModelId id, const char* name, int colmapId) {
    return LensModelInfo{id, name, colmapId, {"f", "cx", "cy", "k"}, false, nullptr, &formula,
                         {}, {},   {}};
  };
  EXPECT_NE(
      errorOf([&] { registerLensModel(row(LensModelId(1001), "OPENCV", 1001)); }).find("OPENCV"),
      std::string::npos);
  EXPECT_NE(errorOf([&] { registerLensModel(row(LensModelId(1001), "X", 4)); }).find("taken"),
            std::string::npos);
  LensModelInfo none = row(LensModelId(1001), "X", 1001);
  none.formula = nullptr;
  EXPECT_NE(errorOf([&] { registerLensModel(none); }).find("exactly one formula"),
            std::string::npos);
  EXPECT_EQ(findLensModelByColmapId(1001), nullptr);
}

}  // namespace
}  // namespace aperture
