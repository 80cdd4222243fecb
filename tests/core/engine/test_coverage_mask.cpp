// The coverage mask (core/engine/coverage_mask.h, RenderSettings::coverageMask): the frame loop
// resolves the packets whose block sees no occupied cell (core/engine/occupancy.h, tested in
// test_occupancy.cpp) as misses without Embree. Checked three ways: the rays the cameras
// generate project into their own pixel through the projection the mask uses (and a flipped
// convention is caught); every pixel the unmasked frame loop hits lies in a covered block, over
// many random poses, while far blocks are left uncovered (and a mask built with the rows flipped
// is caught); and every AOV and count is bit-identical with the mask on and off.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/coverage_mask.h"
#include "core/engine/occupancy.h"
#include "core/engine/packet.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace coverage_mask_test {

/// The mesh placed once as loaded and once turned and moved (an Embree instance).
std::vector<SceneObject> placedTwice(const Mesh& mesh) {
  return test::placedTwice(mesh, {40.0, -5.0, 12.0});
}

/// Perspective cameras of every variant the mask serves, and calibrated pinholes in both
/// pixel-centre conventions.
std::vector<CameraParams> projectiveCameras() {
  std::vector<CameraParams> all;
  CameraParams p = test::lookAt({30.0, 12.0, 60.0}, {20.0, 0.0, 5.0}, 61, 43);
  all.push_back(p);
  CameraParams samples = p;
  samples.spp = 4;
  all.push_back(samples);
  CameraParams shifted = p;
  shifted.shift = glm::dvec2(0.3, -0.2);
  all.push_back(shifted);
  CameraParams architectural = p;
  architectural.architectural = true;
  all.push_back(architectural);
  CameraParams close = p;  // cells beside and behind the eye: clipped before projection
  close.eye = {22.0, 3.0, 14.0};
  close.fovDeg = 100;
  all.push_back(close);
  for (const char* centre : {"half-integer", "integer"}) {
    CameraParams c = p;
    c.type = "calibrated";
    c.fovDeg.reset();
    c.intrinsics = std::vector<double>{50.0, 52.0, 30.0, 21.0};
    c.lensModel = "PINHOLE";
    c.pixelCentre = centre;
    all.push_back(c);
  }
  return all;
}

/// How far (in pixels, beyond its own) the rays of every pixel and sample of `camera` land
/// from their pixel through `p`, the largest over the image.
double largestPixelEscape(const Camera& camera, const CentralProjection& p, int spp) {
  double worst = 0;
  PacketBuffers<16> packet;
  for (int sample = 0; sample < spp; ++sample)
    for (int y0 = 0; y0 < p.height; y0 += 4)
      for (int x0 = 0; x0 < p.width; x0 += 4) {
        const PacketRequest req{x0, y0, 4, 4, spp == 1 ? 0 : sample};
        camera.generate(req, packet.lanes, packet.valid);
        for (int k = 0; k < 16; ++k) {
          const LanePixel px = req.pixel(k);
          if (!packet.valid[k] || !px.inImage(p.width, p.height)) continue;
          const glm::dvec3 o(packet.lanes.orgX[k], packet.lanes.orgY[k], packet.lanes.orgZ[k]);
          const glm::dvec3 d(packet.lanes.dirX[k], packet.lanes.dirY[k], packet.lanes.dirZ[k]);
          const glm::dvec4 h = p.rasterFromRender * glm::dvec4(o + 10.0 * d, 1.0);
          const double x = h.x / h.w, y = h.y / h.w;
          worst =
              std::max({worst, px.column - x, x - (px.column + 1), px.row - y, y - (px.row + 1)});
        }
      }
  return worst;
}

TEST(CentralProjection, EveryRayProjectsIntoItsOwnPixelAndAFlippedRowConventionIsCaught) {
  const glm::dvec3 origin(1.0, 2.0, 3.0);
  for (const CameraParams& p : projectiveCameras()) {
    const std::string what = p.type + " " + p.pixelCentre;
    const auto camera = makeCamera(p, origin);
    const std::optional<CentralProjection> projection = centralProjectionOf(*camera, origin);
    ASSERT_TRUE(projection.has_value()) << what;
    EXPECT_GT(projection->minDepthRate, 0.0) << what;
    EXPECT_LT(largestPixelEscape(*camera, *projection, p.spp), 1e-4) << what;
    // Rows counted from the bottom (OpenGL's window convention) put the rays far from their
    // pixels: the check above would fail.
    CentralProjection flipped = *projection;
    const glm::dmat4 flipRows(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, -1, 0, 0),
                              glm::dvec4(0, 0, 1, 0), glm::dvec4(0, p.height, 0, 1));
    flipped.rasterFromRender = flipRows * flipped.rasterFromRender;
    EXPECT_GT(largestPixelEscape(*camera, flipped, p.spp), 1.0) << what;
  }
}

/// Pixels (and samples) of the image of `camera` whose generated lane is invalid or not
/// finite.
int pixelsWithoutFiniteRay(const Camera& camera, int width, int height, int spp) {
  int n = 0;
  PacketBuffers<16> packet;
  for (int sample = 0; sample < spp; ++sample)
    for (int y0 = 0; y0 < height; y0 += 4)
      for (int x0 = 0; x0 < width; x0 += 4) {
        const PacketRequest req{x0, y0, 4, 4, spp == 1 ? 0 : sample};
        camera.generate(req, packet.lanes, packet.valid);
        const RayLanes& l = packet.lanes;
        for (int k = 0; k < 16; ++k) {
          if (!req.pixel(k).inImage(width, height)) continue;
          const bool finite = std::isfinite(l.orgX[k]) && std::isfinite(l.orgY[k]) &&
                              std::isfinite(l.orgZ[k]) && std::isfinite(l.dirX[k]) &&
                              std::isfinite(l.dirY[k]) && std::isfinite(l.dirZ[k]);
          n += int(!packet.valid[k] || !finite);
        }
      }
  return n;
}

// The frame loop neither generates nor traces the packets of blocks the mask leaves
// uncovered, and counts every lane in the image as a ray resolved: right only if each camera
// with a projection gives every pixel a finite ray.
TEST(CentralProjection, EveryPixelOfACameraWithOneHasAFiniteRay) {
  const glm::dvec3 origin(1.0, 2.0, 3.0);
  for (const CameraParams& p : projectiveCameras()) {
    const auto camera = makeCamera(p, origin);
    ASSERT_TRUE(centralProjectionOf(*camera, origin).has_value());
    EXPECT_EQ(pixelsWithoutFiniteRay(*camera, p.width, p.height, p.spp), 0)
        << p.type << " " << p.pixelCentre << " spp " << p.spp;
  }
  // The count can fail: a distorted lens has pixels without a ray (past its fold).
  CameraParams folded = test::calibratedOpenCvLike(projectiveCameras().front());
  folded.distortion = std::vector<double>{-0.8, 0.0, 0.0, 0.0};  // folds at r_d 0.43
  EXPECT_GT(pixelsWithoutFiniteRay(*makeCamera(folded, origin), folded.width, folded.height, 1), 0);
}

TEST(CentralProjection, OnlyProjectiveCamerasFromOneEyeHaveOne) {
  const glm::dvec3 origin(0.0);
  CameraParams p = test::lookAt({30.0, 12.0, 60.0}, {20.0, 0.0, 5.0}, 61, 43);
  EXPECT_TRUE(centralProjectionOf(*makeCamera(p, origin), origin).has_value());
  CameraParams lens = p;
  lens.type = "thinlens";
  lens.apertureRadius = 1.5;
  lens.focusDistance = 60.0;
  EXPECT_FALSE(centralProjectionOf(*makeCamera(lens, origin), origin).has_value());
  CameraParams clipped = p;
  clipped.clip = glm::dvec2(55.0, 70.0);
  EXPECT_FALSE(centralProjectionOf(*makeCamera(clipped, origin), origin).has_value());
  for (const char* type : {"equirect", "fisheye"}) {
    CameraParams pano = p;
    pano.type = type;
    pano.fovDeg.reset();
    EXPECT_FALSE(centralProjectionOf(*makeCamera(pano, origin), origin).has_value()) << type;
  }
  const CameraParams distorted = test::calibratedOpenCvLike(p);
  EXPECT_FALSE(centralProjectionOf(*makeCamera(distorted, origin), origin).has_value());
}

/// The frame of `p` with every geometry AOV; `mask` sets RenderSettings::coverageMask.
Framebuffer renderWith(const Scene& scene, const CameraParams& p, bool mask, int packet,
                       RenderStats& stats) {
  RenderSettings rs;
  rs.packetWidth = packet;
  rs.tileSize = 8;
  rs.coverageMask = mask;
  return test::render(scene, p, parseAovList("all"), &stats, rs);
}

/// Pixels hit in `fb` (the centre ray's primID) whose block `mask` does not cover.
int uncoveredHits(const Framebuffer& fb, const CoverageMask& mask) {
  int n = 0;
  for (int i = 0; i < fb.height; ++i)
    for (int j = 0; j < fb.width; ++j)
      if (fb.primId[size_t(i) * size_t(fb.width) + size_t(j)] != kInvalidId && !mask.covers(i, j))
        ++n;
  return n;
}

/// A mask of `p` with its rows flipped: the wrong convention the test must catch.
std::optional<CoverageMask> flippedMask(const OccupancyGrid& grid, CentralProjection p) {
  const glm::dmat4 flipRows(glm::dvec4(1, 0, 0, 0), glm::dvec4(0, -1, 0, 0), glm::dvec4(0, 0, 1, 0),
                            glm::dvec4(0, p.height, 0, 1));
  p.rasterFromRender = flipRows * p.rasterFromRender;
  return coverageMaskOf(grid, p);
}

/// The scene of the random-pose tests: procedural spheres placed twice (placedTwice).
struct RandomPoseScene {
  Mesh mesh = loadMesh("procedural:spheres?tris=3000");
  Scene scene{test::numericsDevice(), placedTwice(mesh)};
};

/// Pose number `pose` of the random-pose tests: an eye around the scene of placedTwice (some
/// inside its box) looking at a point near it, on a small image whose size varies.
CameraParams randomPose(std::mt19937& rng, int pose) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const glm::dvec3 centre(20.0, -2.0, 6.0);
  const glm::dvec3 eye = centre + glm::dvec3(60 * unit(rng), 30 * unit(rng), 60 * unit(rng));
  const glm::dvec3 at = centre + glm::dvec3(25 * unit(rng), 10 * unit(rng), 25 * unit(rng));
  return test::lookAt(eye, at, 64 + pose % 5, 48 + pose % 3);
}

TEST(CoverageMask, EveryHitPixelIsCoveredFromRandomPosesAndAFlippedMaskIsCaught) {
  const RandomPoseScene setup;
  const Scene& scene = setup.scene;
  ASSERT_NE(scene.occupancy(), nullptr);
  std::mt19937 rng(7);
  int masks = 0, flippedCaught = 0, tight = 0;
  for (int pose = 0; pose < 60; ++pose) {
    CameraParams p = randomPose(rng, pose);
    p.fovDeg = 30 + (pose * 7) % 70;
    const std::string what = "pose " + std::to_string(pose);
    RenderStats stats;
    const Framebuffer fb = renderWith(scene, p, false, 16, stats);
    const auto camera = makeCamera(p, scene.renderOrigin());
    const std::optional<CentralProjection> projection =
        centralProjectionOf(*camera, scene.renderOrigin());
    ASSERT_TRUE(projection.has_value()) << what;
    for (const OccupancyGrid& grid : scene.occupancy()->levels) {  // every level
      const std::optional<CoverageMask> mask = coverageMaskOf(grid, *projection);
      if (!mask) continue;  // the eye in an occupied cell
      ++masks;
      EXPECT_EQ(uncoveredHits(fb, *mask), 0) << what << " cell " << grid.cell;
      if (&grid != &scene.occupancy()->levels.front()) continue;
      if (stats.hits > 0 && mask->coveredFraction() < 0.9) ++tight;
      const std::optional<CoverageMask> flipped = flippedMask(grid, *projection);
      if (flipped && uncoveredHits(fb, *flipped) > 0) ++flippedCaught;
    }
  }
  EXPECT_GT(masks, 3 * 45);
  EXPECT_GT(tight, 20);          // the mask leaves background uncovered
  EXPECT_GT(flippedCaught, 20);  // and the check sees a mask in the wrong rows
}

TEST(CoverageMask, CellsBesideTheEyeCoverWhatTheirFrontPartCanShow) {
  // Street level in the city, wide angle: the ground's cells under the eye reach behind it,
  // and the rays at the bottom of the image hit their front part, close to the eye's plane.
  const Mesh mesh = loadMesh("procedural:city");
  const Scene scene(test::numericsDevice(), {SceneObject{&mesh}});
  ASSERT_NE(scene.occupancy(), nullptr);
  const OccupancyGrid* grid = &scene.occupancy()->levels.front();
  int masks = 0;
  for (int pose = 0; pose < 8; ++pose) {
    const double a = 0.8 * pose;
    const glm::dvec3 eye(3.0 * std::cos(a), 0.35, 3.0 * std::sin(a));
    CameraParams p = test::lookAt(eye, eye + glm::dvec3(std::sin(a), -0.05, -std::cos(a)), 80, 60);
    p.fovDeg = 110;
    const std::string what = "pose " + std::to_string(pose);
    RenderStats stats;
    const Framebuffer fb = renderWith(scene, p, false, 16, stats);
    const auto camera = makeCamera(p, scene.renderOrigin());
    const std::optional<CoverageMask> mask =
        coverageMaskOf(*grid, *centralProjectionOf(*camera, scene.renderOrigin()));
    if (!mask) continue;
    ++masks;
    EXPECT_EQ(uncoveredHits(fb, *mask), 0) << what;
  }
  EXPECT_GT(masks, 4);
}

/// A calibrated camera of `p`'s pose and size with a distorted lens: `model` with the
/// horizontal field of view `fovDeg` (f = (W / 2) / tan(fov / 2), principal point at the
/// centre) and `distortion`, at 1 spp.
CameraParams lensCamera(CameraParams p, const char* model, double fovDeg,
                        std::vector<double> distortion) {
  const double f = 0.5 * p.width / std::tan(0.5 * fovDeg * M_PI / 180.0);
  p.type = "calibrated";
  p.fovDeg.reset();
  p.intrinsics = std::vector<double>{f, f, 0.5 * p.width, 0.5 * p.height};
  p.lensModel = model;
  p.distortion = std::move(distortion);
  return p;
}

/// Distorted lenses the lens mask serves: mild and strong OPENCV barrels, a fisheye, one that
/// folds inside the image (pixels without a ray), and COLMAP's integer pixel centres.
std::vector<CameraParams> lensCameras(const CameraParams& pose) {
  std::vector<CameraParams> all{lensCamera(pose, "OPENCV", 60, {-0.1, 0.01, 1e-4, -1e-4}),
                                lensCamera(pose, "OPENCV", 80, {-0.3, 0.08, 0.0, 0.0}),
                                lensCamera(pose, "OPENCV_FISHEYE", 90, {0.05, 0.01, 0.0, 0.0}),
                                lensCamera(pose, "OPENCV", 70, {-0.8, 0.0, 0.0, 0.0})};
  CameraParams integer = all.front();
  integer.pixelCentre = "integer";
  all.push_back(integer);
  return all;
}

/// The largest distance (plane units, relative to 1 + the point's size) by which the ray of a
/// valid lane of `camera` crosses the plane z = 1 outside the bounds `bounds` gives its block
/// (`rowShift` reads the bounds of the block that many rows further down instead: a wrong
/// block the check must catch). Counts the lanes checked in `lanes`.
double largestPlaneEscape(const Camera& camera, const LensBlockBounds& bounds, int rowShift,
                          int& lanes) {
  const int blocksX = (bounds.width + 3) / 4, blocksY = (bounds.height + 3) / 4;
  const glm::dmat3 rotation(bounds.cameraFromRender);
  double worst = 0;
  PacketBuffers<16> packet;
  for (int y0 = 0; y0 < bounds.height; y0 += 4)
    for (int x0 = 0; x0 < bounds.width; x0 += 4) {
      const int blockRow = y0 / 4 + rowShift;
      if (blockRow >= blocksY) continue;
      const PacketRequest req{x0, y0, 4, 4, 0};
      camera.generate(req, packet.lanes, packet.valid);
      const glm::dvec4 b(bounds.blocks[size_t(blockRow) * size_t(blocksX) + size_t(x0 / 4)]);
      for (int k = 0; k < 16; ++k) {
        if (!packet.valid[k] || !req.pixel(k).inImage(bounds.width, bounds.height)) continue;
        const glm::dvec3 d =
            rotation * glm::dvec3(packet.lanes.dirX[k], packet.lanes.dirY[k], packet.lanes.dirZ[k]);
        const glm::dvec2 q(d.x / d.z, d.y / d.z);
        const double scale = 1.0 + std::max(std::fabs(q.x), std::fabs(q.y));
        ++lanes;
        if (!(b.x <= b.z)) {  // a block without a ray in the bounds
          worst = std::max(worst, 1.0);
          continue;
        }
        worst = std::max({worst, (b.x - q.x) / scale, (q.x - b.z) / scale, (b.y - q.y) / scale,
                          (q.y - b.w) / scale});
      }
    }
  return worst;
}

TEST(LensBlockBounds, EveryCentreRayCrossesThePlaneInsideItsBlocksBounds) {
  const glm::dvec3 origin(1.0, 2.0, 3.0);
  const CameraParams pose = test::lookAt({30.0, 12.0, 60.0}, {20.0, 0.0, 5.0}, 61, 43);
  for (const CameraParams& p : lensCameras(pose)) {
    const std::string what = p.lensModel + " " + p.pixelCentre;
    const auto camera = makeCamera(p, origin);
    const std::optional<LensBlockBounds> bounds = camera->lensBlockBounds();
    ASSERT_TRUE(bounds.has_value()) << what;
    int lanes = 0;
    // Within the rounding of the float directions the frame loop traces.
    EXPECT_LT(largestPlaneEscape(*camera, *bounds, 0, lanes), 1e-6) << what;
    EXPECT_GT(lanes, 1000) << what;
    // The bounds of the block below miss rays of this one.
    EXPECT_GT(largestPlaneEscape(*camera, *bounds, 1, lanes), 1e-3) << what;
  }
  // None where a pixel's rays are not all its centre's (spp 4), nor for an undistorted lens
  // (it has a projective map instead).
  CameraParams samples = lensCameras(pose).front();
  samples.spp = 4;
  EXPECT_FALSE(makeCamera(samples, origin)->lensBlockBounds().has_value());
  CameraParams pinhole = lensCameras(pose).front();
  pinhole.lensModel = "PINHOLE";
  pinhole.distortion.reset();
  EXPECT_FALSE(makeCamera(pinhole, origin)->lensBlockBounds().has_value());
}

/// `lens` with each block's bounds taken from the block one row down (the last row without
/// rays): a mask built from it looks at the wrong rows.
struct ShiftedBounds {
  std::vector<glm::vec4> blocks;
  LensBlockBounds lens;
  explicit ShiftedBounds(LensBlockBounds original) : lens(original) {
    const size_t bx = size_t(original.width + 3) / 4, by = size_t(original.height + 3) / 4;
    const float inf = std::numeric_limits<float>::infinity();
    blocks.assign(bx * by, glm::vec4(inf, inf, -inf, -inf));
    for (size_t b = 0; b + bx < bx * by; ++b) blocks[b] = original.blocks[b + bx];
    lens.blocks = blocks.data();
  }
};

TEST(CoverageMask, ThroughALensEveryHitPixelIsCoveredFromRandomPosesAndAShiftedMaskIsCaught) {
  const RandomPoseScene setup;
  const Scene& scene = setup.scene;
  ASSERT_NE(scene.occupancy(), nullptr);
  std::mt19937 rng(11);
  int masks = 0, shiftedCaught = 0, tight = 0;
  for (int pose = 0; pose < 60; ++pose) {
    const std::vector<CameraParams> lenses = lensCameras(randomPose(rng, pose));
    CameraParams p = lenses[size_t(pose) % lenses.size()];
    const std::string what = "pose " + std::to_string(pose) + " " + p.lensModel;
    RenderStats stats;
    const Framebuffer fb = renderWith(scene, p, false, 16, stats);
    const auto camera = makeCamera(p, scene.renderOrigin());
    const LensBlockBounds bounds = *camera->lensBlockBounds();
    ASSERT_GE(bounds.minCosine, kLensMaskMinCosine) << what;
    const CentralProjection plane = lensPlaneProjection(bounds, *camera->sharedRayOrigin());
    const ShiftedBounds shifted(bounds);
    for (const OccupancyGrid& grid : scene.occupancy()->levels) {  // every level
      const std::optional<CoverageMask> onPlane = coverageMaskOf(grid, plane);
      if (!onPlane) continue;  // the eye in an occupied cell
      ++masks;
      const CoverageMask mask = maskThroughLens(*onPlane, bounds);
      EXPECT_EQ(uncoveredHits(fb, mask), 0) << what << " cell " << grid.cell;
      if (&grid != &scene.occupancy()->levels.front()) continue;
      if (stats.hits > 0 && mask.coveredFraction() < 0.9) ++tight;
      if (uncoveredHits(fb, maskThroughLens(*onPlane, shifted.lens)) > 0) ++shiftedCaught;
    }
  }
  EXPECT_GT(masks, 3 * 45);
  EXPECT_GT(tight, 20);          // the finest mask leaves background uncovered
  EXPECT_GT(shiftedCaught, 10);  // and the check sees a mask of the wrong rows
}

TEST(CoverageMask, ThroughALensWiderThanTheLimitGetsNone) {
  const Mesh mesh = loadMesh("procedural:spheres?tris=3000");
  const Scene scene(test::numericsDevice(), {SceneObject{&mesh}});
  const CameraParams pose = test::lookAt({0.0, 0.5, 40.0}, {0.0, 0.0, 0.0}, 160, 120);
  // f = (W / 2) / tan(fov / 2): at "175°" the equidistant fisheye's corners lie 170° off-axis,
  // at "60°" 34°.
  for (const double fov : {60.0, 175.0}) {
    const CameraParams p = lensCamera(pose, "OPENCV_FISHEYE", fov, {0.0, 0.0, 0.0, 0.0});
    const auto camera = makeCamera(p, scene.renderOrigin());
    const LensBlockBounds bounds = *camera->lensBlockBounds();
    EXPECT_EQ(bounds.minCosine<kLensMaskMinCosine, fov> 170) << fov;
    EXPECT_EQ(lensCoverageMask(*scene.occupancy(), bounds, *camera->sharedRayOrigin()).has_value(),
              fov < 170)
        << fov;
  }
}

/// Covered fraction of each level's mask through `projection` (finest first), −1 where it has
/// none.
std::vector<double> levelCoverage(const Scene& scene, const CentralProjection& projection) {
  std::vector<double> covered;
  for (const OccupancyGrid& grid : scene.occupancy()->levels) {
    const std::optional<CoverageMask> mask = coverageMaskOf(grid, projection);
    covered.push_back(mask ? mask->coveredFraction() : -1.0);
  }
  return covered;
}

/// The projection of `p` in `scene`.
CentralProjection projectionOf(const Scene& scene, const CameraParams& p) {
  return *centralProjectionOf(*makeCamera(p, scene.renderOrigin()), scene.renderOrigin());
}

/// The covered fraction of the mask a frame of `p` in `scene` uses (refinedCoverageMask), −1
/// for none.
double refinedCoverage(const Scene& scene, const CameraParams& p) {
  const std::optional<CoverageMask> mask =
      refinedCoverageMask(*scene.occupancy(), projectionOf(scene, p), p.spp);
  return mask ? mask->coveredFraction() : -1.0;
}

TEST(CoverageMask, RefinesOnlyWhileTheLastRefinementResolvedEnoughRays) {
  const Mesh mesh = loadMesh("procedural:city");
  const Scene scene(test::numericsDevice(), {SceneObject{&mesh}});
  const std::vector<OccupancyGrid>& levels = scene.occupancy()->levels;
  const auto pose = [](const glm::dvec3& eye, double fov, int width, int height) {
    CameraParams p = test::lookAt(eye, {0.0, 1.0, 0.0}, width, height);
    p.fovDeg = fov;
    return p;
  };
  const double rays = 1920.0 * 1080.0;
  // From far away the finest level would resolve a little more than the middle one, but the
  // step before it resolved too little to pay for its runs: the middle level is used.
  const CameraParams far = pose({0.0, 0.5, 60.0}, 30, 1920, 1080);
  std::vector<double> c = levelCoverage(scene, projectionOf(scene, far));
  ASSERT_LT(c[0], c[1]);
  ASSERT_FALSE(refinementPays((c[2] - c[1]) * rays, levels[0].runs.size()));
  EXPECT_EQ(refinedCoverage(scene, far), c[1]);
  // Among the towers each refinement resolves much more: the finest level is used.
  const CameraParams street = pose({0.0, 3.0, 10.0}, 60, 1920, 1080);
  c = levelCoverage(scene, projectionOf(scene, street));
  ASSERT_TRUE(refinementPays((c[2] - c[1]) * rays, levels[0].runs.size()));
  EXPECT_EQ(refinedCoverage(scene, street), c[0]);
  // A smaller image projects no level past its run budget (maxCoverageRuns), even where 64
  // samples per pixel would make the refinement pay, and a tiny one none at all.
  CameraParams small = pose({0.0, 3.0, 10.0}, 60, 640, 480);
  small.spp = 64;
  c = levelCoverage(scene, projectionOf(scene, small));
  ASSERT_TRUE(refinementPays((c[2] - c[1]) * 640.0 * 480.0 * 64.0, levels[0].runs.size()));
  ASSERT_LT(levels[1].runs.size(), maxCoverageRuns(640, 480));
  ASSERT_GT(levels[0].runs.size(), maxCoverageRuns(640, 480));
  EXPECT_EQ(refinedCoverage(scene, small), c[1]);
  EXPECT_EQ(refinedCoverage(scene, pose({0.0, 3.0, 10.0}, 60, 8, 8)), -1.0);
  // The eye in an occupied cell of the coarsest level: it gives no mask and does not count as
  // one of the two levels always projected.
  const CameraParams close = pose({1.0, 2.0, 8.0}, 30, 1920, 1080);
  c = levelCoverage(scene, projectionOf(scene, close));
  ASSERT_EQ(c[2], -1.0);
  ASSERT_LT(c[0], c[1]);
  EXPECT_EQ(refinedCoverage(scene, close), c[0]);
}

TEST(CoverageMask, IsNoneWhereEveryLevelCoversTheWholeImage) {
  // Inside a cube, and at street level facing a wall: the masks cover every block, so a
  // frame is better off without one.
  const Mesh cube = loadMesh("procedural:cube");
  const Scene room(test::numericsDevice(), {SceneObject{&cube}});
  const CameraParams inside = test::lookAt({0.1, 0.05, 0.0}, {1.0, 0.2, 0.3}, 320, 240);
  for (const double covered : levelCoverage(room, projectionOf(room, inside)))
    ASSERT_EQ(covered, 1.0);
  EXPECT_EQ(refinedCoverage(room, inside), -1.0);
  const Mesh city = loadMesh("procedural:city");
  const Scene scene(test::numericsDevice(), {SceneObject{&city}});
  CameraParams wall = test::lookAt({0.0, 0.35, 3.0}, {0.0, 1.0, 0.0}, 1920, 1080);
  wall.fovDeg = 60;
  for (const double covered : levelCoverage(scene, projectionOf(scene, wall)))
    ASSERT_TRUE(covered == 1.0 || covered == -1.0);
  EXPECT_EQ(refinedCoverage(scene, wall), -1.0);
}

TEST(CoverageMask, IsMissingWhenTheEyeIsInAnOccupiedCell) {
  const Mesh mesh = loadMesh("procedural:spheres?tris=3000");
  const Scene scene(test::numericsDevice(), {SceneObject{&mesh}});
  ASSERT_NE(scene.occupancy(), nullptr);
  const OccupancyGrid* grid = &scene.occupancy()->levels.front();
  const glm::dvec3 inside = glm::dvec3(mesh.vertex(mesh.indices[0])) + mesh.anchor;
  const CameraParams p = test::lookAt(inside, inside + glm::dvec3(1.0, 0.2, 0.1), 32, 24);
  const auto camera = makeCamera(p, scene.renderOrigin());
  const std::optional<CentralProjection> projection =
      centralProjectionOf(*camera, scene.renderOrigin());
  ASSERT_TRUE(projection.has_value());
  EXPECT_FALSE(coverageMaskOf(*grid, *projection).has_value());
}

TEST(CoverageMaskFrameLoop, EveryAovAndCountIsBitIdenticalWithTheMaskOnAndOff) {
  const Mesh mesh = loadMesh("procedural:spheres?tris=6000");
  const Scene scene(test::numericsDevice(), placedTwice(mesh));
  uint64_t resolvedByMask = 0;
  for (const CameraParams& p : projectiveCameras())
    for (int packet : {1, 4, 8, 16}) {
      const std::string what = p.type + " " + p.pixelCentre + " spp " + std::to_string(p.spp) +
                               " packet " + std::to_string(packet);
      RenderStats on, off;
      const Framebuffer masked = renderWith(scene, p, true, packet, on);
      const Framebuffer unmasked = renderWith(scene, p, false, packet, off);
      test::expectSameFrameFewerEmbreeRays(masked, unmasked, on, off, what);
      EXPECT_GE(on.maskCovered, 0.0) << what << ": the mask applies";
      EXPECT_EQ(off.maskCovered, -1.0) << what;
      if (on.raysOutsideBox > off.raysOutsideBox)
        resolvedByMask += on.raysOutsideBox - off.raysOutsideBox;
    }
  EXPECT_GT(resolvedByMask, 10000u);  // beyond what the box alone resolves
}

TEST(CoverageMaskFrameLoop, EveryAovAndCountIsBitIdenticalThroughALensWithTheMaskOnAndOff) {
  const Mesh mesh = loadMesh("procedural:spheres?tris=6000");
  const Scene scene(test::numericsDevice(), placedTwice(mesh));
  const CameraParams pose = test::lookAt({30.0, 12.0, 60.0}, {20.0, 0.0, 5.0}, 160, 120);
  uint64_t resolvedByMask = 0;
  for (const CameraParams& p : lensCameras(pose))
    for (int packet : {1, 4, 8, 16}) {
      const std::string what =
          p.lensModel + " " + p.pixelCentre + " packet " + std::to_string(packet);
      RenderStats on, off;
      const Framebuffer masked = renderWith(scene, p, true, packet, on);
      const Framebuffer unmasked = renderWith(scene, p, false, packet, off);
      test::expectSameFrameFewerEmbreeRays(masked, unmasked, on, off, what);
      EXPECT_GE(on.maskCovered, 0.0) << what << ": the mask applies";
      if (on.raysOutsideBox > off.raysOutsideBox)
        resolvedByMask += on.raysOutsideBox - off.raysOutsideBox;
    }
  EXPECT_GT(resolvedByMask, 10000u);
}

}  // namespace coverage_mask_test
}  // namespace aperture
