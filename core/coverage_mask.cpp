#include "core/coverage_mask.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "core/parallel.h"

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
    : blocksX_((width + kCoverageBlock - 1) / kCoverageBlock),
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

/// Adds the vertices of the part of a box at depth ≥ minW: its corners there and the points
/// where its 12 edges cross that depth.
template <class Add>
void clipAndAdd(const Homogeneous (&corner)[8], double minW, const Add& add) {
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
}

/// The pixel rectangle (clamped to the image) that may see the part of a box at planar depth
/// ≥ `minW`; empty when that part projects off the image or is empty; nothing when a
/// projection is not finite.
std::optional<PixelRect> projectClipped(const Homogeneous (&corner)[8], double minW, int width,
                                        int height) {
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  bool any = false;
  auto add = [&](const Homogeneous& h) {
    const double inv = 1.0 / h.w, x = h.x * inv, y = h.y * inv;
    x0 = std::min(x0, x), x1 = std::max(x1, x);
    y0 = std::min(y0, y), y1 = std::max(y1, y);
    any = true;
  };
  double nearest = corner[0].w;
  for (int c = 1; c < 8; ++c) nearest = std::min(nearest, corner[c].w);
  if (nearest >= minW) {  // the whole box lies deep enough: its corners bound it
    for (int c = 0; c < 8; ++c) add(corner[c]);
  } else {
    clipAndAdd(corner, minW, add);
  }
  if (!any) return PixelRect{0, 0, -1, -1};
  if (!std::isfinite(x0) || !std::isfinite(x1) || !std::isfinite(y0) || !std::isfinite(y1))
    return std::nullopt;
  // Pixel j may see the box when [j − 1, j + 2) meets [x0, x1]: the sample lies in [j, j + 1),
  // widened by a pixel for the rounding of the ray's direction.
  auto first = [](double lo, int size) {
    return int(std::clamp(std::floor(lo) - 2.0, 0.0, double(size)));
  };
  auto last = [](double hi, int size) {
    return int(std::clamp(std::floor(hi) + 2.0, -1.0, double(size - 1)));
  };
  return PixelRect{first(x0, width), first(y0, height), last(x1, width), last(y1, height)};
}

/// Projects the runs of one grid through one camera (the per-run part of coverageMaskOf).
class RunProjector {
 public:
  RunProjector(const OccupancyGrid& grid, const CentralProjection& p)
      : grid_(grid), p_(p), m_(p.rasterFromRender) {
    const glm::dvec3 depthRow(m_[0][3], m_[1][3], m_[2][3]);
    eyeW_ = glm::dot(depthRow, p.eye) + m_[3][3];
    // Every cell grown by the rounding of the rays' origin (twice, and a little more).
    const glm::dvec3 originError = glm::abs(glm::dvec3(p.rayOrigin) - p.eye);
    grow_ = 2.0 * std::max({originError.x, originError.y, originError.z}) +
            glm::length(p.eye) * 0x1p-40;
    // A float direction is within 2^-23·√3 of the unit one: the rate and the distance each
    // lose at most a part in 10^6.
    rate_ = (p.minDepthRate - 1e-6 * glm::length(depthRow)) * (1.0 - 1e-6);
  }

  /// The pixels that may see the run; nothing when the eye lies in (or at) it, a projection is
  /// not finite, or the run covers the whole image (a mask would then resolve nothing).
  std::optional<PixelRect> rectOf(const OccupiedRun& run) const {
    const glm::dvec3 lo = grid_.lo + grid_.cell * glm::dvec3(run.x0, run.y, run.z) - grow_;
    const glm::dvec3 hi =
        grid_.lo + grid_.cell * glm::dvec3(run.x1 + 1, run.y + 1, run.z + 1) + grow_;
    const double distance = glm::length(glm::max(glm::max(lo - p_.eye, p_.eye - hi), 0.0));
    const double minW = eyeW_ + distance * rate_;
    if (!(distance > 0) || !(minW > 0)) return std::nullopt;
    // A corner's homogeneous raster position is linear in it: the low corner's, plus the
    // columns of the matrix scaled by the box's edges.
    const glm::dvec4 l = m_ * glm::dvec4(lo, 1.0);
    const Homogeneous base{l.x, l.y, l.w},
        edge[3] = {column(0, hi.x - lo.x), column(1, hi.y - lo.y), column(2, hi.z - lo.z)};
    Homogeneous corner[8];
    for (int c = 0; c < 8; ++c) {
      corner[c] = base;
      for (int axis = 0; axis < 3; ++axis)
        if (c & (1 << axis)) {
          corner[c].x += edge[axis].x;
          corner[c].y += edge[axis].y;
          corner[c].w += edge[axis].w;
        }
    }
    const std::optional<PixelRect> r = projectClipped(corner, minW, p_.width, p_.height);
    if (r && r->column0 == 0 && r->row0 == 0 && r->column1 == p_.width - 1 &&
        r->row1 == p_.height - 1)
      return std::nullopt;
    return r;
  }

  /// The rectangle of every run (in parallel); false when a run has none (rectOf).
  bool rectsOf(std::vector<PixelRect>& out) const {
    out.resize(grid_.runs.size());
    std::atomic<bool> unusable{false};
    parallelFor(out.size(), 1024, [&](size_t begin, size_t end) {
      for (size_t k = begin; k != end && !unusable; ++k) {
        const std::optional<PixelRect> r = rectOf(grid_.runs[k]);
        if (!r) unusable = true;
        if (r) out[k] = *r;
      }
    });
    return !unusable;
  }

 private:
  Homogeneous column(int c, double scale) const {
    return {m_[c][0] * scale, m_[c][1] * scale, m_[c][3] * scale};
  }

  const OccupancyGrid& grid_;
  const CentralProjection& p_;
  const glm::dmat4& m_;
  double eyeW_, grow_, rate_;
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
  for (size_t y = 0; y < by; ++y)
    for (size_t x = 1; x < bx; ++x) count[y * stride + x] += count[y * stride + x - 1];
  for (size_t y = 0; y < by; ++y)
    for (size_t x = 0; x < bx; ++x) {
      if (y > 0) count[y * stride + x] += count[(y - 1) * stride + x];
      covered_[y * bx + x] = count[y * stride + x] > 0 ? 1 : 0;
    }
}

std::optional<CoverageMask> coverageMaskOf(const OccupancyGrid& grid, const CentralProjection& p) {
  std::vector<PixelRect> rects;
  if (!RunProjector(grid, p).rectsOf(rects)) return std::nullopt;
  CoverageMask mask(p.width, p.height);
  mask.cover(rects);
  return mask;
}

}  // namespace aperture
