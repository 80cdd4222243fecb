// `camera --export` on the command line, through the `aperture` binary: a lecture perspective
// camera exported in every format, its K worked out here from --fov / --viewport / --shift and
// its centre from --eye, and cameras without a calibrated form or unknown formats refused
// without writing a file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "core/util/units.h"
#include "tests/camera_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using nlohmann::json;
using test::apertureBinary;
using test::expectRefused;
using test::runCommand;

// ---- camera --export ----

/// The sensor and the one image of an exported file.
const CalibratedImage& onlyImage(const CameraFile& f) {
  EXPECT_EQ(f.images.size(), 1u);
  EXPECT_EQ(f.sensors.size(), 1u);
  return f.images.at(0);
}

/// The camera centre −Rᵀt of a world-to-camera matrix.
glm::dvec3 centreOf(const glm::dmat4& cvCameraFromWorld) {
  const glm::dmat3 r(cvCameraFromWorld);
  return -(glm::transpose(r) * glm::dvec3(cvCameraFromWorld[3]));
}

/// A lecture perspective camera exported in every format: K = (W·d/vw, H·d/vh, principal
/// point) and the centre = --eye, worked out here from the flags.
struct ExportCase {
  std::string flags;
  int width, height;
  double fx, fy, cx, cy;  ///< COLMAP's pixel convention
  glm::dvec3 eye, at;
};

void expectExported(const std::string& dir, const ExportCase& c) {
  SCOPED_TRACE(c.flags);
  struct Format {
    const char* name;
    std::string out;
    double toSource;  ///< principal point shift into the file's convention
  } formats[] = {{"colmap", dir + "/colmap", 0.0},
                 {"nerf", dir + "/nerf/transforms.json", 0.0},
                 {"opencv", dir + "/opencv.json", -0.5}};
  for (const Format& f : formats) {
    SCOPED_TRACE(f.name);
    std::string log;
    ASSERT_EQ(runCommand(apertureBinary() + " camera " + c.flags + " --export " + f.name +
                             " --out " + f.out + " --export-image view.png",
                         &log),
              0)
        << log;
    const CameraFile file = readCameraFile(f.out);
    const CalibratedImage& image = onlyImage(file);
    EXPECT_EQ(image.name, "view.png");
    const CalibratedSensor& s = file.sensors.at(0);
    EXPECT_EQ(s.width, c.width);
    EXPECT_EQ(s.height, c.height);
    EXPECT_EQ(s.lens.info().name, std::string("PINHOLE"));
    const std::vector<double> expected = {c.fx, c.fy, c.cx + f.toSource, c.cy + f.toSource};
    ASSERT_EQ(s.lens.params().size(), 4u);
    for (size_t k = 0; k < 4; ++k)
      EXPECT_NEAR(s.lens.params()[k], expected[k], 1e-9 * std::abs(expected[k]) + 1e-12) << k;
    const glm::dvec3 centre = centreOf(image.cvCameraFromWorld);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(centre[k], c.eye[k], 1e-12) << k;
    // OpenCV's z axis (third row of R) looks at --at.
    const glm::dvec3 forward(image.cvCameraFromWorld[0][2], image.cvCameraFromWorld[1][2],
                             image.cvCameraFromWorld[2][2]);
    EXPECT_NEAR(glm::length(forward - glm::normalize(c.at - c.eye)), 0, 1e-12);
  }
}

TEST(CameraFilesCliExport, ALecturePerspectiveCameraInEveryFormat) {
  const std::string dir = test::scratchDir();
  // --fov 40 (vertical) at d = 1: vh = 2 tan 20°, vw = vh·W/H; fx = W/vw = H/vh = fy; the
  // principal point is the image centre.
  const double f = 48 / (2 * std::tan(20 * kPi / 180));
  expectExported(dir + "/fov", {"--eye 1,2,3 --at 0,0.5,0 --up 0,1,0 --fov 40 --size 64,48",
                                64,
                                48,
                                f,
                                f,
                                32,
                                24,
                                {1, 2, 3},
                                {0, 0.5, 0}});
  // --d 2 --viewport 3,2.5 --shift 0.1,0.2: fx = W·d/vw, fy = H·d/vh; the axis (u = v = 0)
  // meets the image at x/W = ½ − shiftX, y/H = ½ + shiftY (y down).
  expectExported(dir + "/shift",
                 {"--eye -2,1,4 --at 0,0,0 --d 2 --viewport 3,2.5 --shift 0.1,0.2 --size 64,48",
                  64,
                  48,
                  64 * 2 / 3.0,
                  48 * 2 / 2.5,
                  64 * 0.4,
                  48 * 0.7,
                  {-2, 1, 4},
                  {0, 0, 0}});
}

TEST(CameraFilesCliExport, CamerasWithoutACalibratedFormAndUnknownFormatsAreRefused) {
  const std::string dir = test::scratchDir();
  const std::string cam = apertureBinary() + " camera --eye 0,0,5 --at 0,0,0 ";
  expectRefused(cam + "--camera orthographic --viewport 2,2 --export colmap --out " + dir + "/o",
                {"orthographic", "no calibrated form"}, dir);
  expectRefused(cam + "--export colmpa --out " + dir + "/o", {"colmpa", "did you mean 'colmap'"},
                dir);
  expectRefused(cam + "--export nerf", {"--out"}, dir);
}

}  // namespace
}  // namespace aperture
