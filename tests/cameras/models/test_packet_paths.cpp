// The vector kernels of the pixel-centre rays (issue 13: parallel projections, thin lens,
// equirect, fisheye, calibrated pinhole and table) against the scalar path: every lane of
// every block shape the frame loop uses, blocks crossing the image's right and bottom edges,
// blocks off the 4-pixel grid, at 1 spp and for the centre ray at spp > 1, must equal
// CameraBase::ray() at samplePosition() rounded to float, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "tests/camera_support.h"

namespace aperture {
namespace {

using test::PacketBuffer;

struct KernelCase {
  std::string name;
  CameraParams params;
};

std::vector<KernelCase> kernelCases() {
  std::vector<KernelCase> v;
  CameraParams o = test::tiltedParams("orthographic");
  o.viewport = glm::dvec2(3.0, 2.0);
  v.push_back({"orthographic", o});
  o.type = "oblique";
  o.obliqueAnglesDeg = glm::dvec2(30.0, -20.0);
  v.push_back({"oblique", o});
  CameraParams t = test::tiltedParams("thinlens");
  t.fovDeg = 40;
  t.apertureRadius = 0.2;
  t.focusDistance = 4.0;
  v.push_back({"thinlens", t});
  t.shift = {0.1, -0.2};
  v.push_back({"thinlens_shift", t});
  CameraParams e = test::tiltedParams("equirect");
  v.push_back({"equirect", e});
  e.longitudeRangeDeg = {-60.0, 100.0};
  e.latitudeRangeDeg = {-30.0, 45.0};
  v.push_back({"equirect_ranges", e});
  CameraParams f = test::tiltedParams("fisheye");
  f.fisheyeFovDeg = 230;
  v.push_back({"fisheye_230", f});
  f.fisheyeFovDeg = 180;
  v.push_back({"fisheye_180", f});
  // Calibrated intrinsics as fractions of the image size (test::sizedCamera).
  CameraParams c = test::tiltedParams("calibrated");
  c.lensModel = "PINHOLE";
  c.intrinsics = std::vector<double>{0.9, 0.8, 0.55, 0.45};
  v.push_back({"calibrated_pinhole", c});
  c.pixelCentre = "integer";
  v.push_back({"calibrated_pinhole_integer", c});
  c.pixelCentre = "half-integer";
  c.lensModel = "OPENCV";  // zero distortion: the closed-form path
  c.distortion = std::vector<double>{0.0, 0.0, 0.0, 0.0};
  v.push_back({"calibrated_opencv_undistorted", c});
  c.distortion = std::vector<double>{-0.2, 0.05, 1e-3, -5e-4};  // the table path
  v.push_back({"calibrated_opencv", c});
  c.lensModel = "OPENCV_FISHEYE";
  c.intrinsics = std::vector<double>{0.3, 0.3, 0.5, 0.5};
  c.distortion = std::vector<double>{0.0, 0.0, 0.0, 0.0};
  v.push_back({"calibrated_opencv_fisheye", c});
  return v;
}

struct Shape {
  int blockW, blockH, packetWidth;
};
const Shape kShapes[] = {{4, 4, 16}, {4, 2, 8}, {2, 2, 4}, {1, 1, 1}};

/// Compares every lane of the blocks of one shape, tiled from (startX, startY), with the
/// scalar path for sample s; counts the lanes outside the image it checked in `outside`.
void checkBlocks(const CameraBase& cam, const CameraParams& p, const Shape& shape, int startX,
                 int startY, int s, int& outside) {
  for (int y0 = startY; y0 < p.height; y0 += shape.blockH)
    for (int x0 = startX; x0 < p.width; x0 += shape.blockW) {
      PacketBuffer buf(shape.packetWidth);
      int valid[16];
      const PacketRequest req{x0, y0, shape.blockW, shape.blockH, s};
      cam.generate(req, buf.lanes(), valid);
      const RayLanes& l = buf.lanes();
      for (int k = 0; k < req.lanes(); ++k) {
        const LanePixel px = req.pixel(k);
        SCOPED_TRACE(testing::Message() << "block (" << x0 << ", " << y0 << ") lane " << k
                                        << " pixel (" << px.row << ", " << px.column << ")");
        double x, y, lx = 0.5, ly = 0.5;
        cam.samplePosition(px.row, px.column, s, x, y);
        if (p.apertureRadius > 0) cam.lensSample(px.row, px.column, s, lx, ly);
        glm::dvec3 org, dir;
        const bool has = cam.ray(x, y, lx, ly, org, dir);
        const bool inImage = px.inImage(p.width, p.height);
        outside += !inImage;
        ASSERT_EQ(valid[k], (has && inImage) ? -1 : 0);
        // Bit patterns: +0 and −0 differ, as they do in the golden hashes.
        auto bits = [](float f) {
          uint32_t u;
          std::memcpy(&u, &f, 4);
          return u;
        };
        ASSERT_EQ(bits(l.orgX[k]), bits(float(org.x)));
        ASSERT_EQ(bits(l.orgY[k]), bits(float(org.y)));
        ASSERT_EQ(bits(l.orgZ[k]), bits(float(org.z)));
        ASSERT_EQ(bits(l.dirX[k]), bits(float(dir.x)));
        ASSERT_EQ(bits(l.dirY[k]), bits(float(dir.y)));
        ASSERT_EQ(bits(l.dirZ[k]), bits(float(dir.z)));
        ASSERT_NO_FATAL_FAILURE(test::assertFixedLaneFields(l, k));
      }
    }
}

class PacketPaths : public ::testing::TestWithParam<int> {};

TEST_P(PacketPaths, PixelCentreKernelsEqualTheScalarPathBitForBit) {
  const KernelCase kc = kernelCases()[size_t(GetParam())];
  // Odd and even sizes (the fisheye's mirror symmetry differs), neither a multiple of 4.
  for (const glm::ivec2 size : {glm::ivec2(13, 7), glm::ivec2(18, 10), glm::ivec2(11, 14)}) {
    for (const int spp : {1, 4}) {
      SCOPED_TRACE(testing::Message()
                   << kc.name << " " << size.x << "x" << size.y << " spp " << spp);
      CameraParams p = kc.params;
      p.width = size.x;
      p.height = size.y;
      p.spp = spp;
      p = test::sizedCamera(p);
      const auto cam = makeCameraModel(p, glm::dvec3(-2.0, 0.5, 1.5));
      // 1 spp: sample 0 is the pixel centre; spp > 1: the centre ray (the kernels' requests).
      const int s = spp == 1 ? 0 : PacketRequest::kCentreRay;
      for (const Shape& shape : kShapes) {
        SCOPED_TRACE(testing::Message() << shape.blockW << "x" << shape.blockH);
        int outside = 0;
        checkBlocks(*cam, p, shape, 0, 0, s, outside);
        if (::testing::Test::HasFatalFailure()) return;
        // Where the edges cut the blocks, the lanes past them were checked too.
        if (p.width % shape.blockW != 0 || p.height % shape.blockH != 0) {
          EXPECT_GT(outside, 0);
        }
        // Blocks off the 4-pixel grid (not the frame loop's, but allowed by the contract).
        checkBlocks(*cam, p, shape, 1, 1, s, outside);
        if (::testing::Test::HasFatalFailure()) return;
      }
    }
  }
}

std::string caseName(const ::testing::TestParamInfo<int>& info) {
  return kernelCases()[size_t(info.param)].name;
}

INSTANTIATE_TEST_SUITE_P(EveryKernel, PacketPaths, ::testing::Range(0, int(kernelCases().size())),
                         caseName);

}  // namespace
}  // namespace aperture
