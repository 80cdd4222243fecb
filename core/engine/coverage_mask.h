#pragma once
// The blocks of a camera's image that can see anything: the scene's occupied cells
// (core/engine/occupancy.h) projected through the camera's projective map. A packet whose block no
// cell covers is a miss without calling Embree, like the rays the scene-box test resolves,
// but the mask follows the shape of the geometry rather than its box: around a scan the
// background inside its box is resolved too.
//
// For cameras whose rays all start at one point (Camera::sharedRayOrigin) and follow a
// projective map (CameraDescription::ndcFromWorld): pinhole perspective cameras and
// undistorted calibrated ones. Conservative by construction, so images are bit-identical with
// and without it. For a ray of pixel (i, j) from the float eye o' along the float direction
// d' that hits P = o' + t·d':
//  - Q = e + t·d' (e the exact eye) lies within |o' − e| of P, so in an occupied cell grown by
//    that much (every cell is grown by it);
//  - Q seen from e lies along d', whose raster position is within rounding of the sample's,
//    which lies in pixel (i, j): the projected rectangle of the grown cell, widened by two
//    pixels, holds the pixel;
//  - every hit has planar depth at least (distance from e to the cell) · (the smallest cosine
//    of a ray of the image with the view axis), so each cell is clipped to that depth before
//    it is projected: a cell beside or behind the eye covers only what it can.
// A frame whose eye lies in an occupied cell gets no mask, nor one where a single cell covers
// the whole image (an interior seen from inside): such a mask would resolve nothing.
// A distorted lens at 1 spp (Camera::lensBlockBounds) gets one too: the cells are projected
// onto a raster of the plane z = 1 of its camera frame, and each block of the image is covered
// where its rays' crossings of that plane meet a covered block there (lensCoverageMask).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <optional>
#include <vector>

#include "core/engine/camera.h"
#include "core/engine/occupancy.h"

namespace aperture {

/// Pixels per side of a mask block: a packet's block (at most 4x4, aligned) lies in one.
inline constexpr int kCoverageBlock = 4;

/// Runs a mask may project per block of its image: its cost grows with the runs, its saving
/// with the blocks, so a small image takes only coarse occupancy levels (refinedCoverageMask).
/// At 0.5 a mask costs about 8 instructions per pixel (a run about 250).
inline constexpr double kCoverageRunsPerBlock = 0.5;

/// The most runs a mask of a width x height image projects (kCoverageRunsPerBlock).
inline size_t maxCoverageRuns(int width, int height) {
  const double blocks = double((width + kCoverageBlock - 1) / kCoverageBlock) *
                        double((height + kCoverageBlock - 1) / kCoverageBlock);
  return size_t(blocks * kCoverageRunsPerBlock);
}

/// A camera's projective map from render space, as the coverage mask needs it.
struct CentralProjection {
  /// Homogeneous raster from render space (GLM column vectors): raster x = row 0 / row 3,
  /// y = row 1 / row 3, pixel (i, j) centre at (j + ½, i + ½); row 3 is positive in front.
  glm::dmat4 rasterFromRender{1.0};
  glm::dvec3 eye{0.0};        ///< exact eye, render space
  glm::vec3 rayOrigin{0.0f};  ///< the rays' float origin (Camera::sharedRayOrigin)
  int width = 0, height = 0;
  /// The smallest value of row 3's linear part · d over the unit directions d of the
  /// image's rays (its corners widened by two pixels); positive.
  double minDepthRate = 0;
};

/// The projection of `camera` in a scene whose render origin is `renderOrigin`, or nothing when
/// the camera has no shared ray origin or no projective map (CameraDescription::ndcFromWorld).
std::optional<CentralProjection> centralProjectionOf(const Camera& camera,
                                                     const glm::dvec3& renderOrigin);

/// Pixels [column0, column1] x [row0, row1], inclusive; empty when an end passes the other.
struct PixelRect {
  int column0, row0, column1, row1;
  bool empty() const { return column0 > column1 || row0 > row1; }
};

class CoverageMask;

/// The least cosine with the lens's axis of the rays of a camera that gets a mask through its
/// lens (lensCoverageMask): wider lenses spread the plane z = 1 too far for its raster.
inline constexpr double kLensMaskMinCosine = 0.1;

/// The mask of a camera with a distorted lens (Camera::lensBlockBounds): the occupancy is
/// projected (refinedCoverageMask) onto a raster of the plane z = 1 of the camera frame, as
/// many pixels as the image over the plane's extent, and a block of the image is covered
/// where its bounds on the plane meet a covered block of that raster. Nothing when the lens
/// is wider than kLensMaskMinCosine allows or no mask would resolve anything.
std::optional<CoverageMask> lensCoverageMask(const Occupancy& occupancy,
                                             const LensBlockBounds& lens,
                                             const glm::vec3& rayOrigin);

/// lensCoverageMask's projection onto the plane's raster: the extent of the plane z = 1 that
/// `lens`'s rays cross, over as many pixels as the image (x and y scaled apart).
CentralProjection lensPlaneProjection(const LensBlockBounds& lens, const glm::vec3& rayOrigin);

/// Pixels of the plane's raster (lensPlaneProjection) per unit of the plane, along x and y.
inline glm::dvec2 lensPlaneScale(const LensBlockBounds& lens) {
  return {lens.width / (lens.extent.z - lens.extent.x),
          lens.height / (lens.extent.w - lens.extent.y)};
}

class CoverageMask {
 public:
  CoverageMask(int width, int height);
  /// Whether the block holding pixel (row, column) may see an occupied cell.
  bool covers(int row, int column) const { return covered_[blockOf(row, column)] != 0; }
  /// Pixels with a ray among the w x h pixels at (row, column), which lie in one block: every
  /// one inside the image for a projective camera (each gives every pixel a finite ray), the
  /// lens's for a mask through a lens (LensBlockBounds::blockRays). The frame loop counts an
  /// uncovered packet's rays with it instead of generating them.
  int raysIn(int row, int column, int w, int h) const {
    if (!blockRays_) return std::min(w, width_ - column) * std::min(h, height_ - row);
    const int r = row % kCoverageBlock, c = column % kCoverageBlock;
    uint32_t lanes = 0;
    for (int k = 0; k < h; ++k) lanes |= ((1u << w) - 1u) << (kCoverageBlock * (r + k) + c);
    return __builtin_popcount(blockRays_[blockOf(row, column)] & lanes);
  }
  /// Fraction of the image's blocks covered.
  double coveredFraction() const;

 private:
  friend std::optional<CoverageMask> coverageMaskOf(const OccupancyGrid&, const CentralProjection&);
  friend CoverageMask maskThroughLens(const CoverageMask&, const LensBlockBounds&);
  /// Marks the blocks the rectangles cover (each block stays covered once covered).
  void cover(const std::vector<PixelRect>& rects);

  size_t blockOf(int row, int column) const {
    return size_t(row / kCoverageBlock) * size_t(blocksX_) + size_t(column / kCoverageBlock);
  }

  int width_, height_;
  int blocksX_, blocksY_;
  std::vector<uint8_t> covered_;
  /// A mask through a lens: its blocks' rays (LensBlockBounds::blockRays), else null.
  const uint16_t* blockRays_ = nullptr;
};

/// The mask of a lens's image from `onPlane`, a mask of its plane's raster
/// (lensPlaneProjection): a block is covered where its bounds meet a covered block there.
CoverageMask maskThroughLens(const CoverageMask& onPlane, const LensBlockBounds& lens);

/// The mask of `grid` seen through `projection`; nothing (then every ray is traced) when the eye
/// lies in an occupied cell, a projection is not finite, or one cell covers the whole image.
std::optional<CoverageMask> coverageMaskOf(const OccupancyGrid& grid,
                                           const CentralProjection& projection);

/// Projecting one run costs about as much as tracing this many of the rays a mask resolves:
/// a run took 24 ns and an average bunny ray 7 ns (wall time at 2 threads, AMD Zen 4), and a
/// resolved ray would have been a miss, cheaper than the average (bench/RESULTS.md, sixth
/// session).
inline constexpr double kRaysPerRun = 5;

/// Whether projecting a finer level of `nextRuns` runs pays, when the last refinement
/// resolved `lastGain` more rays: the gains of successive levels shrink, so the last one
/// bounds the next.
inline bool refinementPays(double lastGain, size_t nextRuns) {
  return lastGain > kRaysPerRun * double(nextRuns);
}

/// The mask a frame uses: the levels of `occupancy` within maxCoverageRuns, coarsest first, the
/// two coarsest always (an interior seen from inside resolves nothing at either and stops
/// there; a coarse level can cover a whole image its finer ones do not), each finer one while
/// refinementPays. A finer level's cells lie in the coarser ones, so its mask covers no block
/// the coarser one leaves. `raysPerPixel` weighs a block by the rays it saves. Nothing when no
/// level gives a mask or the finest one projected covers every block (it would resolve
/// nothing).
std::optional<CoverageMask> refinedCoverageMask(const Occupancy& occupancy,
                                                const CentralProjection& projection,
                                                int raysPerPixel);

}  // namespace aperture
