#include "core/engine/coverage_mask.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <vector>

#include "core/util/parallel.h"
#include "core/util/vector_kernel.h"

namespace aperture {

std::optional<CentralProjection> centralProjectionOf(const Camera& camera,
                                                     const glm::dvec3& renderOrigin) {
  const std::optional<glm::vec3> origin = camera.sharedRayOrigin();
  const CameraDescription d = camera.describe();
  if (!origin || !d.ndcFromWorld || d.width <= 0 || d.height <= 0) return std::nullopt;
  CentralProjection p;
  p.width = d.width;
  p.height = d.height;
  p.eye = d.eye - renderOrigin;
  p.rayOrigin = *origin;
  const glm::dmat4 rasterFromNdc = glm::scale(glm::dmat4(1.0), glm::dvec3(d.width, d.height, 1));
  p.rasterFromRender =
      rasterFromNdc * *d.ndcFromWorld * glm::translate(glm::dmat4(1.0), renderOrigin);
  const glm::dvec3 depthRow(p.rasterFromRender[0][3], p.rasterFromRender[1][3],
                            p.rasterFromRender[2][3]);
  // The rate is 1 / |the ray's point on the plane row 3 = 1|, convex in raster position, so
  // its minimum over the (widened) image is at a corner.
  p.minDepthRate = std::numeric_limits<double>::infinity();
  for (const double x : {-2.0, d.width + 2.0})
    for (const double y : {-2.0, d.height + 2.0}) {
      glm::dvec3 org, dir;
      if (!camera.centreRayAt(x, y, org, dir)) return std::nullopt;
      p.minDepthRate = std::min(p.minDepthRate, glm::dot(depthRow, dir));
    }
  if (!(p.minDepthRate > 1e-6 * glm::length(depthRow))) return std::nullopt;
  return p;
}

CoverageMask::CoverageMask(int width, int height)
    : width_(width),
      height_(height),
      blocksX_((width + kCoverageBlock - 1) / kCoverageBlock),
      blocksY_((height + kCoverageBlock - 1) / kCoverageBlock),
      covered_(size_t(blocksX_) * size_t(blocksY_), 0) {}

double CoverageMask::coveredFraction() const {
  if (covered_.empty()) return 0;
  return double(std::count(covered_.begin(), covered_.end(), uint8_t(1))) / double(covered_.size());
}

namespace {

/// Homogeneous raster position: x and y before the divide by w.
struct Homogeneous {
  double x, y, w;
};

/// The first and last pixel (column or row, clamped to [0, size)) that may see raster
/// positions [lo, hi] along one axis, both finite: pixel j may when [j − 1, j + 2) meets
/// [lo, hi] (a sample lies in [j, j + 1), widened by a pixel for the rounding of the ray's
/// direction). Empty (first > last) when the span lies off the image. Branch-free, so the
/// batch kernel's lane loop vectorises through it.
inline void pixelSpan(double lo, double hi, int size, int& first, int& last) {
  first = int(std::clamp(std::floor(lo) - 2.0, 0.0, double(size)));
  last = int(std::clamp(std::floor(hi) + 2.0, -1.0, double(size - 1)));
}

/// The pixels that may see raster positions [x0, x1] x [y0, y1] (pixelSpan on each axis);
/// nothing when a bound is not finite.
std::optional<PixelRect> pixelsSeeing(double x0, double x1, double y0, double y1, int width,
                                      int height) {
  if (!finiteLane(x0) || !finiteLane(x1) || !finiteLane(y0) || !finiteLane(y1)) return std::nullopt;
  PixelRect r;
  pixelSpan(x0, x1, width, r.column0, r.column1);
  pixelSpan(y0, y1, height, r.row0, r.row1);
  return r;
}

/// The pixels that may see the part of a box (its corners' homogeneous raster positions) at
/// planar depth ≥ `minW`: its corners there and the points where its 12 edges cross that
/// depth bound it. Empty when no part lies there; nothing when a projection is not finite.
std::optional<PixelRect> projectClipped(const Homogeneous (&corner)[8], double minW, int width,
                                        int height) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  bool any = false;
  auto add = [&](const Homogeneous& h) {
    const double inv = 1.0 / h.w, x = h.x * inv, y = h.y * inv;
    x0 = std::min(x0, x), x1 = std::max(x1, x);
    y0 = std::min(y0, y), y1 = std::max(y1, y);
    any = true;
  };
  for (int c = 0; c < 8; ++c) {
    if (corner[c].w >= minW) add(corner[c]);
    for (int axis = 0; axis < 3; ++axis) {  // the box's 12 edges, each once
      const int bit = 1 << axis;
      if (c & bit) continue;
      const Homogeneous &a = corner[c], &b = corner[c | bit];
      if ((a.w >= minW) == (b.w >= minW)) continue;
      const double s = (minW - a.w) / (b.w - a.w);  // the edge's point at depth minW
      add(Homogeneous{a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), minW});
    }
  }
  if (!any) return PixelRect{0, 0, -1, -1};
  return pixelsSeeing(x0, x1, y0, y1, width, height);
}

/// Runs one call of boundRunCorners takes (a constant, so its lane loops vectorise).
constexpr int kRunBatch = 64;

/// A camera's map and a grid's placement as plain numbers, for boundRunCorners.
struct RunProjection {
  double gridLo[3], cell;
  double grow;     ///< every cell grown by this (the rounding of the rays' origin)
  double eye[3];   ///< exact eye, render space
  double eyeW;     ///< depth row of the map at the eye (0 up to rounding)
  double rate;     ///< least depth gained per unit of distance along a ray of the image
  double m[4][4];  ///< homogeneous raster from render space, m[column][row]
  int width, height;
};

/// The runs of one batch, lane by lane: their boxes' corners' homogeneous raster positions,
/// the nearest corner's depth, and the least depth a hit in the box can have (distance from
/// the eye times the rate).
struct RunBatch {
  alignas(64) double cornerX[8][kRunBatch], cornerY[8][kRunBatch], cornerW[8][kRunBatch];
  alignas(64) double nearest[kRunBatch], distance[kRunBatch], minW[kRunBatch];
  /// The pixels the corners' bounds give (pixelSpan), valid where `bounded` is set: every
  /// bound finite.
  alignas(64) int column0[kRunBatch], column1[kRunBatch], row0[kRunBatch], row1[kRunBatch];
  alignas(64) int bounded[kRunBatch];
};

/// Fills `out` for runs[0 .. kRunBatch) (the caller pads a short batch by repeating a run).
/// Each box is the run's cells grown by p.grow; a corner's position is linear in it: the low
/// corner's, plus the matrix's columns scaled by the box's edges. A per-ISA kernel.
void boundRunCorners(const RunProjection& p, const OccupiedRun* runs, RunBatch& out) {
  APERTURE_LANE_LOOP
  for (int k = 0; k < kRunBatch; ++k) {
    const OccupiedRun& r = runs[k];
    const double lo[3] = {p.gridLo[0] + p.cell * r.x0 - p.grow, p.gridLo[1] + p.cell * r.y - p.grow,
                          p.gridLo[2] + p.cell * r.z - p.grow};
    const double hi[3] = {p.gridLo[0] + p.cell * (r.x1 + 1) + p.grow,
                          p.gridLo[1] + p.cell * (r.y + 1) + p.grow,
                          p.gridLo[2] + p.cell * (r.z + 1) + p.grow};
    // Inner loops unrolled whole, so the lane loop around them vectorises.
    double distance2 = 0;
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) {
      const double gap = std::max(std::max(lo[a] - p.eye[a], p.eye[a] - hi[a]), 0.0);
      distance2 += gap * gap;
    }
    out.distance[k] = std::sqrt(distance2);
    out.minW[k] = p.eyeW + out.distance[k] * p.rate;
    double h[8][3];  // the corners' [x, y, w]; corner c takes hi on axis a where bit a is set
#pragma GCC unroll 3
    for (int row = 0; row < 3; ++row) {
      const int mr = row == 2 ? 3 : row;
      const double e0 = p.m[0][mr] * (hi[0] - lo[0]), e1 = p.m[1][mr] * (hi[1] - lo[1]),
                   e2 = p.m[2][mr] * (hi[2] - lo[2]);
      const double base = p.m[0][mr] * lo[0] + p.m[1][mr] * lo[1] + p.m[2][mr] * lo[2] + p.m[3][mr];
      h[0][row] = base, h[1][row] = base + e0, h[2][row] = base + e1, h[3][row] = base + e0 + e1;
      h[4][row] = base + e2, h[5][row] = h[1][row] + e2, h[6][row] = h[2][row] + e2;
      h[7][row] = h[3][row] + e2;
    }
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY, nearest = INFINITY;
#pragma GCC unroll 8
    for (int c = 0; c < 8; ++c) {
      out.cornerX[c][k] = h[c][0], out.cornerY[c][k] = h[c][1], out.cornerW[c][k] = h[c][2];
      const double inv = 1.0 / h[c][2], x = h[c][0] * inv, y = h[c][1] * inv;
      x0 = std::min(x0, x), x1 = std::max(x1, x);
      y0 = std::min(y0, y), y1 = std::max(y1, y);
      nearest = std::min(nearest, h[c][2]);
    }
    out.nearest[k] = nearest;
    const int bounded =
        int(finiteLane(x0)) & int(finiteLane(x1)) & int(finiteLane(y0)) & int(finiteLane(y1));
    out.bounded[k] = bounded;
    // Non-finite bounds replaced by 0 before the conversions to int (their result unused).
    pixelSpan(bounded ? x0 : 0.0, bounded ? x1 : 0.0, p.width, out.column0[k], out.column1[k]);
    pixelSpan(bounded ? y0 : 0.0, bounded ? y1 : 0.0, p.height, out.row0[k], out.row1[k]);
  }
}

/// Projects the runs of one grid through one camera (the per-run part of coverageMaskOf).
class RunProjector {
 public:
  RunProjector(const OccupancyGrid& grid, const CentralProjection& p) : grid_(grid) {
    const glm::dmat4& m = p.rasterFromRender;
    const glm::dvec3 depthRow(m[0][3], m[1][3], m[2][3]);
    for (int a = 0; a < 3; ++a) {
      c_.gridLo[a] = grid.lo[a];
      c_.eye[a] = p.eye[a];
    }
    c_.cell = grid.cell;
    c_.eyeW = glm::dot(depthRow, p.eye) + m[3][3];
    // Every cell grown by the rounding of the rays' origin (twice, and a little more).
    const glm::dvec3 originError = glm::abs(glm::dvec3(p.rayOrigin) - p.eye);
    c_.grow = 2.0 * std::max({originError.x, originError.y, originError.z}) +
              glm::length(p.eye) * 0x1p-40;
    // A float direction is within 2^-23·√3 of the unit one: the rate and the distance each
    // lose at most a part in 10^6.
    c_.rate = (p.minDepthRate - 1e-6 * glm::length(depthRow)) * (1.0 - 1e-6);
    for (int column = 0; column < 4; ++column)
      for (int row = 0; row < 4; ++row) c_.m[column][row] = m[column][row];
    c_.width = p.width;
    c_.height = p.height;
  }

  /// The rectangle of every run (in parallel, a batch at a time); false when the eye lies in
  /// (or at) a run, a projection is not finite, or a run covers the whole image (a mask would
  /// then resolve nothing).
  bool rectsOf(std::vector<PixelRect>& out) const {
    const size_t n = grid_.runs.size();
    out.resize(n);
    std::atomic<bool> unusable{false};
    parallelFor((n + kRunBatch - 1) / kRunBatch, 16, [&](size_t begin, size_t end) {
      RunBatch batch;
      OccupiedRun runs[kRunBatch];
      for (size_t b = begin; b != end && !unusable; ++b) {
        const size_t first = b * kRunBatch, count = std::min(n - first, size_t(kRunBatch));
        for (size_t k = 0; k < size_t(kRunBatch); ++k)
          runs[k] = grid_.runs[first + std::min(k, count - 1)];
        runKernel<&boundRunCorners>(c_, runs, batch);
        for (size_t k = 0; k < count; ++k) {
          const std::optional<PixelRect> r = rectOf(batch, int(k));
          if (!r) unusable = true;
          if (r) out[first + k] = *r;
        }
      }
    });
    return !unusable;
  }

 private:
  /// Lane k's rectangle: from its corners' bounds when the whole box lies deep enough, else
  /// from the box clipped to the least depth a hit can have (projectClipped).
  std::optional<PixelRect> rectOf(const RunBatch& b, int k) const {
    if (!(b.distance[k] > 0) || !(b.minW[k] > 0)) return std::nullopt;
    std::optional<PixelRect> r;
    if (b.nearest[k] >= b.minW[k]) {
      if (!b.bounded[k]) return std::nullopt;
      r = PixelRect{b.column0[k], b.row0[k], b.column1[k], b.row1[k]};
    } else {
      Homogeneous corner[8];
      for (int c = 0; c < 8; ++c) corner[c] = {b.cornerX[c][k], b.cornerY[c][k], b.cornerW[c][k]};
      r = projectClipped(corner, b.minW[k], c_.width, c_.height);
    }
    if (r && r->column0 == 0 && r->row0 == 0 && r->column1 == c_.width - 1 &&
        r->row1 == c_.height - 1)
      return std::nullopt;
    return r;
  }

  const OccupancyGrid& grid_;
  RunProjection c_;
};

}  // namespace

void CoverageMask::cover(const std::vector<PixelRect>& rects) {
  const size_t bx = size_t(blocksX_), by = size_t(blocksY_), stride = bx + 1;
  // Each rectangle adds 1 inside it through its four corners; two passes of prefix sums turn
  // the corner marks into counts of covering rectangles.
  std::vector<int> count(stride * (by + 1), 0);
  for (const PixelRect& r : rects) {
    if (r.empty()) continue;
    const size_t x0 = size_t(r.column0 / kCoverageBlock),
                 x1 = size_t(r.column1 / kCoverageBlock) + 1;
    const size_t y0 = size_t(r.row0 / kCoverageBlock), y1 = size_t(r.row1 / kCoverageBlock) + 1;
    count[y0 * stride + x0] += 1;
    count[y0 * stride + x1] -= 1;
    count[y1 * stride + x0] -= 1;
    count[y1 * stride + x1] += 1;
  }
  for (size_t y = 0; y < by; ++y) {
    int* row = count.data() + y * stride;
    for (size_t x = 1; x < bx; ++x) row[x] += row[x - 1];
  }
  for (size_t y = 0; y < by; ++y) {
    int* __restrict row = count.data() + y * stride;
    const int* __restrict above = row - stride;
    uint8_t* __restrict covered = covered_.data() + y * bx;
    if (y > 0)
      for (size_t x = 0; x < bx; ++x) row[x] += above[x];
    for (size_t x = 0; x < bx; ++x) covered[x] = row[x] > 0 ? 1 : 0;
  }
}

std::optional<CoverageMask> coverageMaskOf(const OccupancyGrid& grid, const CentralProjection& p) {
  std::vector<PixelRect> rects;
  if (!RunProjector(grid, p).rectsOf(rects)) return std::nullopt;
  CoverageMask mask(p.width, p.height);
  mask.cover(rects);
  return mask;
}

std::optional<CoverageMask> refinedCoverageMask(const Occupancy& occupancy,
                                                const CentralProjection& p, int raysPerPixel) {
  const size_t maxRuns = maxCoverageRuns(p.width, p.height);
  const double rays = double(p.width) * double(p.height) * double(raysPerPixel);
  std::optional<CoverageMask> finest;
  double resolved = 0, lastGain = 0;
  int projected = 0;
  for (auto level = occupancy.levels.rbegin(); level != occupancy.levels.rend(); ++level) {
    if (level->runs.size() > maxRuns) continue;  // over this frame's budget
    if (projected >= 2 && !refinementPays(lastGain, level->runs.size())) break;
    std::optional<CoverageMask> mask = coverageMaskOf(*level, p);
    if (!mask) continue;  // the eye in one of its (larger) occupied cells: try a finer one
    ++projected;
    const double levelResolved = (1.0 - mask->coveredFraction()) * rays;
    lastGain = levelResolved - resolved;
    resolved = levelResolved;
    finest = std::move(mask);
  }
  if (finest && finest->coveredFraction() == 1.0) return std::nullopt;
  return finest;
}

CentralProjection lensPlaneProjection(const LensBlockBounds& lens, const glm::vec3& rayOrigin) {
  const glm::dvec4 e = lens.extent;
  const glm::dvec2 scale = lensPlaneScale(lens);
  const double sx = scale.x, sy = scale.y;
  // Rows of the camera frame (GLM: m[column][row]); raster x = sx·(c.x − x0·c.z) / c.z.
  const glm::dmat4& c = lens.cameraFromRender;
  CentralProjection p;
  for (int column = 0; column < 4; ++column) {
    const double cx = c[column][0], cy = c[column][1], cz = c[column][2];
    p.rasterFromRender[column] = glm::dvec4(sx * (cx - e.x * cz), sy * (cy - e.y * cz), cz, cz);
  }
  p.eye = lens.eye;
  p.rayOrigin = rayOrigin;
  p.width = lens.width;
  p.height = lens.height;
  p.minDepthRate = lens.minCosine;  // row 3's linear part is the unit z axis
  return p;
}

CoverageMask maskThroughLens(const CoverageMask& onPlane, const LensBlockBounds& lens) {
  static_assert(kCoverageBlock == 4, "LensBlockBounds::blocks are 4 x 4 pixels");
  // A ray of a block crosses the plane inside the block's bounds; its raster pixel there lies
  // in the plane mask's covered blocks if the occupancy can be on it (the projection's rects
  // are widened by two raster pixels, which covers the rounding of the float direction). The
  // plane's raster has the image's density, so a block's bounds span one to four of its blocks.
  const size_t pbx = size_t(onPlane.blocksX_), pby = size_t(onPlane.blocksY_);
  const glm::dvec4 e = lens.extent;
  const glm::dvec2 scale = lensPlaneScale(lens);
  const double sx = scale.x, sy = scale.y;
  // Truncation is the floor of the clamped, non-negative raster position (and needs no libm
  // call in the portable build).
  const auto blockOf = [](double raster, size_t blocks) {
    return size_t(std::clamp(raster, 0.0, double(kCoverageBlock * blocks - 1))) / kCoverageBlock;
  };
  CoverageMask mask(lens.width, lens.height);
  mask.blockRays_ = lens.blockRays;
  const size_t bx = size_t(mask.blocksX_);
  parallelFor(size_t(mask.blocksY_), 16, [&](size_t firstRow, size_t lastRow) {
    for (size_t b = firstRow * bx; b < lastRow * bx; ++b) {
      const glm::dvec4 r(lens.blocks[b]);
      if (!(r.x <= r.z && r.y <= r.w)) continue;  // no ray: the frame loop traces none
      const size_t x0 = blockOf((r.x - e.x) * sx, pbx), x1 = blockOf((r.z - e.x) * sx, pbx);
      const size_t y0 = blockOf((r.y - e.y) * sy, pby), y1 = blockOf((r.w - e.y) * sy, pby);
      const uint8_t* top = onPlane.covered_.data() + y0 * pbx;
      const uint8_t* bottom = onPlane.covered_.data() + y1 * pbx;
      uint8_t seen = top[x0] | top[x1] | bottom[x0] | bottom[x1];  // the usual 2 x 2 at most
      if (x1 > x0 + 1 || y1 > y0 + 1)
        for (size_t y = y0; y <= y1; ++y)
          for (size_t x = x0; x <= x1; ++x) seen |= onPlane.covered_[y * pbx + x];
      mask.covered_[b] = seen;
    }
  });
  return mask;
}

std::optional<CoverageMask> lensCoverageMask(const Occupancy& occupancy,
                                             const LensBlockBounds& lens,
                                             const glm::vec3& rayOrigin) {
  const glm::dvec4 e = lens.extent;
  if (!(lens.minCosine >= kLensMaskMinCosine) || !(e.z > e.x) || !(e.w > e.y) || !lens.blocks)
    return std::nullopt;
  const std::optional<CoverageMask> onPlane =
      refinedCoverageMask(occupancy, lensPlaneProjection(lens, rayOrigin), 1);
  if (!onPlane) return std::nullopt;
  CoverageMask mask = maskThroughLens(*onPlane, lens);
  if (mask.coveredFraction() == 1.0) return std::nullopt;
  return mask;
}

}  // namespace aperture
