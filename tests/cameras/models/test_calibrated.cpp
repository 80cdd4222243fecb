// The calibrated camera model: its rays against the lecture's perspective camera and against
// closed forms, its pixel and axis conventions (and that a wrong one is caught), its pose
// matrices, the misses past a lens fold and its description.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "cameras/lenses/direction_table.h"
#include "cameras/models/base.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/param_schema.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

CameraParams lecturePerspective() {
  CameraParams p;
  p.eye = {1.25, -0.5, 3.0};
  p.at = glm::dvec3(-0.75, 0.25, -2.0);
  p.up = {0.1, 1.0, 0.2};
  p.width = 37;  // odd sizes: the principal point is not on a pixel edge
  p.height = 23;
  p.fovDeg = 50;
  return p;
}

CameraParams calibratedPinhole(double fx, double fy, double cx, double cy) {
  CameraParams p = lecturePerspective();
  p.type = "calibrated";
  p.fovDeg.reset();
  p.intrinsics = std::vector<double>{fx, fy, cx, cy};
  return p;
}

/// The largest angle (radians, as the chord |da − db|: acos loses half the digits near 0)
/// between the rays of two cameras over every pixel centre and
/// a few off-centre positions.
double largestRayAngle(const CameraBase& a, const CameraBase& b, double offsetX = 0,
                       double offsetY = 0) {
  double worst = 0;
  for (int i = 0; i < a.height(); ++i)
    for (int j = 0; j < a.width(); ++j)
      for (double f : {0.5, 0.1, 0.9}) {
        glm::dvec3 oa, da, ob, db;
        const bool ha = a.ray(j + f, i + f, 0.5, 0.5, oa, da);
        const bool hb = b.ray(j + f + offsetX, i + f + offsetY, 0.5, 0.5, ob, db);
        EXPECT_TRUE(ha && hb);
        EXPECT_LT(glm::length(oa - ob), 1e-12);
        worst = std::max(worst, glm::length(da - db));
      }
  return worst;
}

// A PINHOLE calibrated camera with K = (W·d/vw, H·d/vh, principal point) is the lecture's
// perspective camera: rays agree everywhere to rounding.
TEST(CalibratedCamera, PinholeIsTheLecturePerspectiveCamera) {
  for (glm::dvec2 shift : {glm::dvec2(0.0), glm::dvec2(0.2, -0.35)}) {
    CameraParams lp = lecturePerspective();
    lp.shift = shift;
    const auto lecture = makeCameraModel(lp);
    // K from the lecture's formulas: u = ((x/W) − ½ + sx)·vw at d, so fx = W·d/vw and the
    // principal point (u = 0) is at x = (½ − sx)·W; v = (½ − y/H + sy)·vh, y = (½ + sy)·H.
    const double W = lp.width, H = lp.height, d = lecture->d();
    const double fx = W * d / lecture->vw(), fy = H * d / lecture->vh();
    const auto cal =
        makeCameraModel(calibratedPinhole(fx, fy, (0.5 - shift.x) * W, (0.5 + shift.y) * H));
    EXPECT_LT(largestRayAngle(*lecture, *cal), 1e-14);
    // calibratedViewOf derives the same K from the description.
    const std::optional<CalibratedView> view = calibratedViewOf(lecture->describe());
    ASSERT_TRUE(view);
    EXPECT_NEAR(view->sensor.lens.fx(), fx, 1e-12 * fx);
    EXPECT_NEAR(view->sensor.lens.cx(), (0.5 - shift.x) * W, 1e-12 * W);
    EXPECT_NEAR(view->sensor.lens.cy(), (0.5 + shift.y) * H, 1e-12 * H);
    const auto back =
        makeCameraModel(calibratedCameraParams(view->sensor, view->cvCameraFromWorld));
    EXPECT_LT(largestRayAngle(*lecture, *back), 1e-14);
  }
}

// OpenCV puts pixel (i, j)'s centre at (j, i): the same lens given with pixel_centre integer
// and cx, cy half a pixel lower is the same camera. Reading OpenCV's cx as COLMAP's (the
// wrong convention) moves every ray by half a pixel, which the check sees.
TEST(CalibratedCamera, IntegerPixelCentresAreHalfAPixelOff) {
  const auto colmap = makeCameraModel(calibratedPinhole(30, 31, 18.5, 11.5));
  CameraParams cv = calibratedPinhole(30, 31, 18.0, 11.0);
  cv.pixelCentre = "integer";
  EXPECT_LT(largestRayAngle(*colmap, *makeCameraModel(cv)), 1e-14);
  cv.pixelCentre = "half-integer";  // the wrong convention for these numbers
  const auto wrong = makeCameraModel(cv);
  EXPECT_GT(largestRayAngle(*colmap, *wrong), 0.3 / 31);           // about half a pixel at f = 30
  EXPECT_LT(largestRayAngle(*colmap, *wrong, -0.5, -0.5), 1e-14);  // exactly half a pixel
}

// Closed form: an undistorted pixel (x, y) looks along R^T ((x − cx)/fx, (y − cy)/fy, 1) with
// OpenCV axes x right, y down; image right is U, image down is −V, forward is −W.
TEST(CalibratedCamera, RayIsTheClosedFormInOpenCvAxes) {
  const auto cam = makeCameraModel(calibratedPinhole(30, 31, 18.5, 11.5));
  const CameraFrame& f = cam->frame();
  for (glm::dvec2 px : {glm::dvec2(0.5, 0.5), glm::dvec2(36.5, 22.5), glm::dvec2(18.5, 11.5)}) {
    glm::dvec3 org, dir;
    ASSERT_TRUE(cam->ray(px.x, px.y, 0.5, 0.5, org, dir));
    const glm::dvec3 expect =
        glm::normalize((px.x - 18.5) / 30 * f.u - (px.y - 11.5) / 31 * f.v - f.w);
    EXPECT_LT(glm::length(dir - expect), 1e-15);
  }
  // A y-up reading (v = +(y − cy)/fy) would send the top row downwards: it is caught.
  glm::dvec3 org, top;
  cam->ray(18.5, 0.5, 0.5, 0.5, org, top);
  EXPECT_GT(glm::dot(top, f.v), 0.0);
}

/// Row-major world-to-camera in OpenCV axes from the lecture frame, built here independently.
std::vector<double> cvCameraFromWorldRowMajor(const CameraFrame& f) {
  const glm::dvec3 rows[3] = {f.u, -f.v, -f.w};
  std::vector<double> m(16, 0.0);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[size_t(4 * r + c)] = rows[r][c];
    m[size_t(4 * r + 3)] = -glm::dot(rows[r], f.e);
  }
  m[15] = 1;
  return m;
}

/// The inverse of a rigid row-major 4x4, and its axes flipped to OpenGL (y, z negated rows).
std::vector<double> invertRigid(const std::vector<double>& m) {
  const glm::dmat4 g = matrixOfRowMajor(m);
  return rowMajor(glm::inverse(g));
}
std::vector<double> flipYZRows(const std::vector<double>& m) {
  std::vector<double> f = m;
  for (int c = 0; c < 4; ++c) {
    f[size_t(4 + c)] = -f[size_t(4 + c)];
    f[size_t(8 + c)] = -f[size_t(8 + c)];
  }
  return f;
}

// The same pose as world-to-camera or camera-to-world, in OpenCV, OpenGL or Blender axes,
// gives the camera eye / at / up give; reading an OpenGL matrix as OpenCV turns it around.
TEST(CalibratedCamera, PoseMatricesInEveryConventionAgree) {
  const CameraParams base = calibratedPinhole(30, 31, 18.5, 11.5);
  const auto reference = makeCameraModel(base);
  const std::vector<double> cvCameraFromWorld = cvCameraFromWorldRowMajor(reference->frame());
  const std::vector<double> glCameraFromWorld = flipYZRows(cvCameraFromWorld);
  struct Case {
    const char* convention;
    bool poseIsWorldFromCamera;
    std::vector<double> m;
  };
  const std::vector<Case> cases = {{"opencv", false, cvCameraFromWorld},
                                   {"opencv", true, invertRigid(cvCameraFromWorld)},
                                   {"opengl", false, glCameraFromWorld},
                                   {"opengl", true, invertRigid(glCameraFromWorld)},
                                   {"blender", true, invertRigid(glCameraFromWorld)}};
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.convention) + (c.poseIsWorldFromCamera ? " c2w" : " w2c"));
    CameraParams p = base;
    p.at.reset();
    p.eye = glm::dvec3(0.0);
    p.up = glm::dvec3(0, 1, 0);
    p.convention = c.convention;
    (c.poseIsWorldFromCamera ? p.worldFromSourceCamera : p.sourceCameraFromWorld) = c.m;
    EXPECT_LT(largestRayAngle(*reference, *makeCameraModel(p)), 1e-13);
  }
  CameraParams wrong = base;
  wrong.at.reset();
  wrong.sourceCameraFromWorld = glCameraFromWorld;  // an OpenGL matrix read as OpenCV
  EXPECT_GT(largestRayAngle(*reference, *makeCameraModel(wrong)), 1.9);  // nearly opposite
  // A matrix that is not a rotation is refused, naming the flag.
  std::vector<double> sheared = cvCameraFromWorld;
  sheared[1] += 0.1;
  wrong.sourceCameraFromWorld = sheared;
  try {
    makeCameraModel(wrong);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--world-to-camera"), std::string::npos) << e.what();
  }
}

// SIMPLE_RADIAL with k = −0.5 folds at r = √(2/3) (d(r + k r³)/dr = 0), where the distorted
// radius is √(2/3)·(2/3): pixels beyond it have no ray, pixels inside have one.
TEST(CalibratedCamera, PixelsPastTheFoldHaveNoRay) {
  CameraParams p = calibratedPinhole(40, 40, 32, 24);
  p.width = 64;
  p.height = 48;
  p.lensModel = "SIMPLE_RADIAL";
  p.distortion = std::vector<double>{-0.5};
  const auto cam = makeCameraModel(p);
  const double foldDistorted = std::sqrt(2.0 / 3.0) * (2.0 / 3.0);
  int inside = 0, outside = 0;
  for (int i = 0; i < p.height; ++i)
    for (int j = 0; j < p.width; ++j) {
      const double rd = std::hypot((j + 0.5 - 32) / 40, (i + 0.5 - 24) / 40);
      if (std::abs(rd - foldDistorted) < 1e-6) continue;
      glm::dvec3 org, dir;
      const bool has = cam->ray(j + 0.5, i + 0.5, 0.5, 0.5, org, dir);
      EXPECT_EQ(has, rd < foldDistorted) << i << "," << j << " rd " << rd;
      (rd < foldDistorted ? inside : outside)++;
      if (has) {
        const auto back = cam->project(org + 3.0 * dir);
        ASSERT_TRUE(back);
        EXPECT_LT(glm::length(*back - glm::dvec2(j + 0.5, i + 0.5)), 1e-6);
      }
    }
  EXPECT_GT(inside, 500);
  EXPECT_GT(outside, 100);
  // The packet path agrees: every lane past the fold is invalid.
  CameraParams one = p;
  const auto packets = makeCamera(one);
  int invalid = 0;
  for (int y0 = 0; y0 < p.height; y0 += 4)
    for (int x0 = 0; x0 < p.width; x0 += 4) {
      float buf[12][16];
      unsigned ubuf[3][16];
      RayLanes l{16,     buf[0], buf[1], buf[2],  buf[3],  buf[4], buf[5],
                 buf[6], buf[7], buf[8], ubuf[0], ubuf[1], ubuf[2]};
      int valid[16];
      packets->generate({x0, y0, 4, 4, 0}, l, valid);
      for (int k = 0; k < 16; ++k) invalid += valid[k] == 0;
    }
  EXPECT_GE(invalid, outside);
}

// Parameters: the model's coefficient count and single focal length are checked with the
// flag named; --intrinsics alone selects the calibrated camera.
TEST(CalibratedCamera, ParameterErrorsNameTheFlag) {
  auto message = [](const std::string& flags) {
    try {
      makeCameraModel(test::cameraParamsFromFlags(flags));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string base = "--intrinsics 30,30,16,12 --eye 0,0,5 --size 32x24";
  EXPECT_EQ(test::cameraParamsFromFlags(base).type, "calibrated");
  EXPECT_NE(
      message(base + " --lens-model OPENCV --distortion 0.1,0.2")
          .find("--distortion: camera model OPENCV takes 4 coefficients (k1,k2,p1,p2), got 2"),
      std::string::npos);
  EXPECT_NE(message("--intrinsics 30,31,16,12 --eye 0,0,5 --lens-model SIMPLE_RADIAL "
                    "--distortion 0.1")
                .find("one focal length, but fx = 30 and fy = 31 differ"),
            std::string::npos);
  EXPECT_NE(message(base + " --distortion 0.1").find("--lens-model"), std::string::npos);
  EXPECT_NE(message(base + " --lens-model OPENCVV").find("did you mean"), std::string::npos);
  EXPECT_NE(message(base + " --world-to-camera 1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1").find("--eye"),
            std::string::npos);
}

// The description: a distorted lens has no worldToNDC (not projective) but its model and
// parameters; a pinhole's worldToNDC maps a point to its projected pixel over (W, H).
TEST(CalibratedCamera, DescriptionCarriesTheLensAndNdcOnlyWhenProjective) {
  CameraParams p = calibratedPinhole(30, 31, 18.5, 11.5);
  const auto pinhole = makeCameraModel(p);
  const CameraDescription d = pinhole->describe();
  ASSERT_TRUE(d.ndcFromWorld);
  ASSERT_TRUE(d.lens);
  EXPECT_EQ(d.lens->model, "PINHOLE");
  const glm::dvec3 point(0.3, -0.2, -1.0);
  const glm::dvec4 ndc = *d.ndcFromWorld * glm::dvec4(point, 1.0);
  const auto px = pinhole->project(point);
  ASSERT_TRUE(px);
  EXPECT_NEAR(ndc.x / ndc.w * p.width, px->x, 1e-9);
  EXPECT_NEAR(ndc.y / ndc.w * p.height, px->y, 1e-9);

  p.lensModel = "OPENCV";
  p.distortion = std::vector<double>{-0.1, 0.01, 1e-3, 0.0};
  const CameraDescription dd = makeCameraModel(p)->describe();
  EXPECT_FALSE(dd.ndcFromWorld);
  ASSERT_TRUE(dd.lens);
  EXPECT_EQ(dd.lens->model, "OPENCV");
  EXPECT_EQ(dd.lens->params, (std::vector<double>{30, 31, 18.5, 11.5, -0.1, 0.01, 1e-3, 0.0}));
  EXPECT_EQ(dd.lens->pixelCentre, "half-integer");
  bool region = false;
  for (const auto& [k, v] : dd.extra) region |= k == "valid_region";
  EXPECT_TRUE(region);
}

}  // namespace
}  // namespace aperture

namespace aperture {
namespace {

// A distorted camera builds its direction table at its first ray, not when it is made, asked
// where it looks or described without counts (what --resume compares): a job's cameras are
// made when the job is read, and again for the automatic preview range, so 100 distinct
// sensors had every table built twice (bench/RESULTS.md). Its whole description, which counts
// the pixels with a ray, builds it.
TEST(CalibratedCamera, BuildsItsTableAtItsFirstRayNotWhenMade) {
  CameraParams p = calibratedPinhole(30, 31, 18.5, 11.5);
  p.lensModel = "OPENCV";
  p.distortion = std::vector<double>{-0.2, 0.01, 1e-3, 2.5e-4};  // a sensor of this test only
  const CalibratedSensor sensor = calibratedSensorOf(p);
  ASSERT_FALSE(DirectionTable::cached(sensor));
  const auto camera = makeCamera(p);
  const WorldView view = camera->worldView();
  const CameraDescription stated = camera->describeWithoutCounts();
  EXPECT_FALSE(DirectionTable::cached(sensor));
  float buf[12][16];
  unsigned ubuf[3][16];
  RayLanes l{16,     buf[0], buf[1], buf[2],  buf[3],  buf[4], buf[5],
             buf[6], buf[7], buf[8], ubuf[0], ubuf[1], ubuf[2]};
  int valid[16];
  camera->generate({0, 0, 4, 4, 0}, l, valid);
  EXPECT_TRUE(DirectionTable::cached(sensor));
  // The packet's rays are the table's, which is the lens's inverse at the pixel centres.
  const glm::dvec3 d = *sensor.lens.unproject(glm::dvec2(0.5, 0.5));
  EXPECT_EQ(DirectionTable::of(sensor)->at(0, 0), d);
  const CameraDescription described = camera->describe();
  EXPECT_EQ(view.eye, described.eye);
  EXPECT_EQ(view.w, described.w);
  // The description without counts is the description but for its counted extras.
  std::vector<std::pair<std::string, std::string>> uncounted;
  for (const auto& e : described.extra)
    if (!isCountedExtra(e.first)) uncounted.push_back(e);
  EXPECT_EQ(stated.extra, uncounted);
  EXPECT_EQ(uncounted.size() + 1, described.extra.size());  // valid_pixels
  EXPECT_EQ(stated.eye, described.eye);
  EXPECT_EQ(stated.u, described.u);
  EXPECT_EQ(stated.w, described.w);
  EXPECT_EQ(stated.d, described.d);
  EXPECT_EQ(stated.exrCameraFromWorld, described.exrCameraFromWorld);
  ASSERT_TRUE(stated.lens && described.lens);
  EXPECT_EQ(stated.lens->params, described.lens->params);
}

// Images of one sensor share its table (set up once); another lens or size gets its own, and
// the table holds exactly the lens's inverse at every pixel centre, and the optical axis, with
// no ray, wherever there is none: the blocks' padding past the image's edges included (the
// table's buffers are sized without being written, so each entry must be written by its row).
TEST(CalibratedCamera, ImagesOfOneSensorShareOneTable) {
  CameraParams p = calibratedPinhole(30, 31, 18.5, 11.5);
  p.lensModel = "OPENCV";
  p.distortion = std::vector<double>{-0.2, 0.01, 1e-3, 0.0};
  const CalibratedSensor sensor = calibratedSensorOf(p);
  const auto a = DirectionTable::of(sensor);
  CameraParams moved = p;
  moved.eye = {4.0, 1.0, -2.0};
  EXPECT_EQ(DirectionTable::of(calibratedSensorOf(moved)), a);  // a pose is not part of it
  CameraParams other = p;
  other.distortion = std::vector<double>{-0.2, 0.01, 1e-3, 1e-9};
  EXPECT_NE(DirectionTable::of(calibratedSensorOf(other)), a);
  for (int i = 0; i < p.height; ++i)
    for (int j = 0; j < p.width; ++j) {
      const std::optional<glm::dvec3> d =
          sensor.lens.unproject(glm::dvec2(j + 0.5, i + 0.5));  // half-integer convention
      ASSERT_EQ(a->valid(i, j), d.has_value());
      ASSERT_EQ(a->at(i, j), d.value_or(glm::dvec3(0.0, 0.0, 1.0))) << i << "," << j;
    }
  const int kB = DirectionTable::kBlock;
  ASSERT_TRUE(p.width % kB != 0 && p.height % kB != 0) << "the test wants padding on both sides";
  for (int i = 0; i < (p.height + kB - 1) / kB * kB; ++i)
    for (int j = 0; j < (p.width + kB - 1) / kB * kB; ++j) {
      if (i < p.height && j < p.width) continue;
      ASSERT_FALSE(a->valid(i, j)) << i << "," << j;
      ASSERT_EQ(a->at(i, j), glm::dvec3(0.0, 0.0, 1.0)) << i << "," << j;
    }
}

}  // namespace
}  // namespace aperture
