// Equidistant fisheye: the angle from the view axis grows linearly with the distance from
// the image centre.
//
// Raster position (x, y), image W x H pixels, circle radius R = min(W, H) / 2 pixels centred
// at (W / 2, H / 2), full field of view F (degrees, at most 360):
//   a = (x − W/2) / R,  b = (H/2 − y) / R,  rho = sqrt(a² + b²)
//   rho > 1: no ray (valid lane 0, a miss)
//   theta = rho · F / 2                          (angle from −W)
//   dir = sin(theta)·(a/rho·U + b/rho·V) − cos(theta)·W   (−W at rho = 0)
// Origin e. Image right is +U, image up is +V.
#include <cmath>
#include <cstdint>
#include <vector>

#include "cameras/models/camera_models.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/units.h"
#include "core/util/vector_kernel.h"

namespace aperture {

namespace {

/// The trigonometry of the pixel centres, which does not separate into rows and columns (θ
/// grows with ρ = √(a² + b²)), tabulated over one quadrant of the image: the centres of
/// columns j and W − 1 − j lie at exactly opposite a (x − cx is a multiple of ½, so exact,
/// and negated), likewise rows and b, so mirrored pixels share ρ, sin θ / ρ and cos θ bit
/// for bit. Entry (qi, qj) holds pixel (H/2 + qi, W/2 + qj)'s values (integer halves); pixel
/// (i, j) reads entry (|2i + 1 − H| / 2, |2j + 1 − W| / 2). 17 bytes per entry, a quarter of
/// the pixels: 8.9 MB for 1920 x 1080, where a per-pixel table would take 35 MB.
struct FisheyeQuadrant {
  enum Kind : uint8_t { kNoRay = 0, kRay = 1, kAxis = 2 };  ///< ρ > 1, 0 < ρ <= 1, ρ = 0
  int columns = 0, rows = 0;                                ///< entries per row, rows
  std::vector<double> sinOverRho, cosTheta;  ///< sin θ / ρ and cos θ (0 and 1 where no ray)
  std::vector<uint8_t> kind;
};

/// What the pixel-centre kernel needs of the camera.
struct FisheyeCentres {
  const FisheyeQuadrant& quadrant;
  double cx, cy, radius;
  glm::dvec3 u, v, w, eye;
  glm::vec3 axis;  ///< −W rounded: the direction of the centre pixel and of pixels without a ray
  int width, height;
};

/// A kBW x kBH block of rays through pixel centres, FisheyeCamera::rayAt term by term: a and b
/// once per column and row, sin θ / ρ and cos θ from the quadrant table, then
/// g = (s·a)·U + (s·b)·V − cos θ·W and g / |g|; −W where ρ = 0 or there is no ray.
/// The table entries are copied to per-lane arrays first (scalar loads: the entries of a block
/// row run forwards or backwards through the table, or both across the centre column), so the
/// arithmetic is one lane loop over contiguous arrays that the compiler vectorises whole.
template <int kBW, int kBH>
void fisheyeCentres(const FisheyeCentres& c, int x0, int y0, RayLanes& out, int* valid) {
  constexpr int kLanes = kBW * kBH;
  double as[kBW], bs[kBH];
  size_t qjs[kBW], qis[kBH];
  for (int col = 0; col < kBW; ++col) {
    as[col] = (((double(x0) + double(col)) + 0.5) - c.cx) / c.radius;
    const int twice = 2 * (x0 + col) + 1 - c.width;
    qjs[col] = size_t((twice < 0 ? -twice : twice) / 2);
  }
  for (int row = 0; row < kBH; ++row) {
    bs[row] = (c.cy - ((double(y0) + double(row)) + 0.5)) / c.radius;
    const int twice = 2 * (y0 + row) + 1 - c.height;
    qis[row] = size_t((twice < 0 ? -twice : twice) / 2) * size_t(c.quadrant.columns);
  }
  alignas(64) double al[kLanes], bl[kLanes], sl[kLanes], cl[kLanes];
  alignas(64) int kinds[kLanes];
  spreadOverLanes<kBW, kBH>(as, bs, al, bl);
  for (int k = 0; k < kLanes; ++k) {  // lanePixel's order
    const size_t q = qis[k / kBW] + qjs[k % kBW];
    sl[k] = c.quadrant.sinOverRho[q];
    cl[k] = c.quadrant.cosTheta[q];
    kinds[k] = c.quadrant.kind[q];
  }
  const glm::dvec3 U = c.u, V = c.v, W = c.w;
  const glm::vec3 axis = c.axis;
  const int width = c.width, height = c.height;  // locals: the stores to valid[] could alias c
  alignas(64) float dx[kLanes], dy[kLanes], dz[kLanes];
  APERTURE_LANE_LOOP
  for (int k = 0; k < kLanes; ++k) {
    const double sa = sl[k] * al[k], sb = sl[k] * bl[k], cosT = cl[k];
    const double gx = (sa * U.x + sb * V.x) - cosT * W.x;
    const double gy = (sa * U.y + sb * V.y) - cosT * W.y;
    const double gz = (sa * U.z + sb * V.z) - cosT * W.z;
    const double length = std::sqrt((gx * gx + gy * gy) + gz * gz);
    // Divided on every lane, then selected: a divide under the condition stays scalar.
    const float ux = float(gx / length), uy = float(gy / length), uz = float(gz / length);
    const bool ray = kinds[k] == FisheyeQuadrant::kRay;
    dx[k] = ray ? ux : axis.x;
    dy[k] = ray ? uy : axis.y;
    dz[k] = ray ? uz : axis.z;
    valid[k] = -(int(kinds[k] != FisheyeQuadrant::kNoRay) &
                 int(laneInImage(x0, y0, kBW, k, width, height)));
  }
  writeBlockLanesFromOrigin<kLanes>(out, c.eye, dx, dy, dz);
}

class FisheyeCamera final : public PacketCamera<FisheyeCamera> {
 public:
  FisheyeCamera(const CameraParams& p, const glm::dvec3& renderOrigin)
      : PacketCamera(p, renderOrigin, "fisheye") {
    rejectShift();
    halfFov_ = 0.5 * p.fisheyeFovDeg * kRadPerDeg;
    radius_ = 0.5 * std::min(width_, height_);
    cx_ = 0.5 * width_;
    cy_ = 0.5 * height_;
    buildQuadrant();
  }

  /// Rays through pixel centres (every sample at 1 spp, the centre ray at any spp) in the
  /// frame loop's block shapes take the quadrant-table kernel; everything else the packet loop.
  /// Every ray starts at the eye, at tnear 0.
  std::optional<glm::vec3> sharedRayOrigin() const override { return renderEye_; }

  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    if (spp_ == 1 || req.centreRay()) {
      const FisheyeCentres c{quadrant_, cx_,         cy_,
                             radius_,   frame_.u,    frame_.v,
                             frame_.w,  renderEyeD_, glm::vec3(-frame_.w),
                             width_,    height_};
      const bool done = withBlockShape(req.blockW, req.blockH, [&](auto bw, auto bh) {
        constexpr int kBW = decltype(bw)::value, kBH = decltype(bh)::value;
        runKernel<&fisheyeCentres<kBW, kBH>>(c, req.x0, req.y0, out, valid);
      });
      if (done) return;
    }
    PacketCamera::generate(req, out, valid);
  }

  bool usesLens() const { return false; }
  bool rayAt(double x, double y, double, double, glm::dvec3& org, glm::dvec3& dir) const {
    const double a = (x - cx_) / radius_, b = (cy_ - y) / radius_;
    const double rho = std::sqrt(a * a + b * b);
    org = renderEyeD_;
    if (rho > 1.0) {
      dir = -frame_.w;
      return false;
    }
    if (rho == 0.0) {
      dir = -frame_.w;
      return true;
    }
    const double theta = rho * halfFov_, s = std::sin(theta) / rho;
    const glm::dvec3 g = (s * a) * frame_.u + (s * b) * frame_.v - std::cos(theta) * frame_.w;
    dir = g / glm::length(g);
    return true;
  }

  std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const override {
    const glm::dvec3 p = worldPoint - frame_.e;
    const double x = glm::dot(p, frame_.u), y = glm::dot(p, frame_.v), z = glm::dot(p, frame_.w);
    const double lateral = std::hypot(x, y);
    if (lateral == 0 && z == 0) return std::nullopt;
    const double theta = std::atan2(lateral, -z);
    if (theta > halfFov_) return std::nullopt;
    if (lateral == 0) return glm::dvec2(cx_, cy_);
    const double rho = theta / halfFov_;
    return glm::dvec2(cx_ + radius_ * rho * x / lateral, cy_ - radius_ * rho * y / lateral);
  }

  ViewVolume viewVolume(double nearDist, double farDist) const override {
    return ViewVolume::allSpace(frame_.e, frame_.u, frame_.v, frame_.w, nearDist, farDist);
  }

 protected:
  void describeExtra(CameraDescription& c) const override {
    c.fisheye = FisheyeProjection{params_.fisheyeFovDeg, glm::dvec2(cx_, cy_), radius_};
    c.pixelAspectRatio = 1.0;  // the angle grows with the distance in pixels, alike on both axes
  }

 private:
  /// Fills quadrant_ with rayAt's ρ, sin θ / ρ and cos θ, with entries past the image's right
  /// and bottom edges for the lanes of blocks that cross them.
  void buildQuadrant() {
    // A lane at most 3 pixels past the edge, column W + 2, reads entry |2(W + 2) + 1 − W| / 2.
    FisheyeQuadrant& q = quadrant_;
    q.columns = (width_ + 5) / 2 + 1;
    q.rows = (height_ + 5) / 2 + 1;
    const size_t n = size_t(q.columns) * size_t(q.rows);
    q.sinOverRho.assign(n, 0.0);
    q.cosTheta.assign(n, 1.0);
    q.kind.assign(n, FisheyeQuadrant::kNoRay);
    parallelFor(size_t(q.rows), 16, [&](size_t rowBegin, size_t rowEnd) {
      for (size_t qi = rowBegin; qi < rowEnd; ++qi)
        for (int qj = 0; qj < q.columns; ++qj) {
          const double x = double(width_ / 2 + qj) + 0.5, y = double(height_ / 2 + int(qi)) + 0.5;
          const double a = (x - cx_) / radius_, b = (cy_ - y) / radius_;
          const double rho = std::sqrt(a * a + b * b);
          const size_t k = qi * size_t(q.columns) + size_t(qj);
          if (rho > 1.0) continue;
          if (rho == 0.0) {
            q.kind[k] = FisheyeQuadrant::kAxis;
            continue;
          }
          const double theta = rho * halfFov_;
          q.sinOverRho[k] = std::sin(theta) / rho;
          q.cosTheta[k] = std::cos(theta);
          q.kind[k] = FisheyeQuadrant::kRay;
        }
    });
  }

  double halfFov_ = 0, radius_ = 1, cx_ = 0, cy_ = 0;
  FisheyeQuadrant quadrant_;
};

const ParamSpec kFisheyeFov =
    ParamSpec("fisheye_fov", ParamKind::Number, fieldAccess<&CameraParams::fisheyeFovDeg>())
        .withUnit("degrees")
        .withHelp("Full field of view of the image circle")
        .withRange(ParamRange::openClosed(0.0, 360.0));

std::unique_ptr<CameraBase> makeFisheyeCamera(const CameraParams& p,
                                              const glm::dvec3& renderOrigin) {
  return std::make_unique<FisheyeCamera>(p, renderOrigin);
}

}  // namespace

const CameraModel& fisheyeModel() {
  static const CameraModel m{"fisheye", "equidistant fisheye: angle from the axis ~ radius",
                             makeFisheyeCamera,
                             joinParamSpecs({commonParamSpecs(), {&kFisheyeFov}})};
  return m;
}

}  // namespace aperture
