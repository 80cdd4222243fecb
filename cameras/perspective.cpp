// Perspective camera of the lecture: origin e, direction u·U + v·V − d·W, normalised; the
// window may be shifted (params.shift, or the tilt of the architectural mode).
#include "cameras/perspective.h"

#include <cmath>
#include <limits>

#include "cameras/models.h"
#include "core/error.h"

namespace aperture {

namespace {
constexpr double kDegPerRad = 57.295779513082320877;
}  // namespace

PerspectiveCamera::PerspectiveCamera(const CameraParams& p, const glm::dvec3& renderOrigin,
                                     const char* typeName, double lensRadius,
                                     double focusDistance)
    : PacketCamera(p, renderOrigin, typeName),
      lensRadius_(lensRadius),
      focusDistance_(focusDistance),
      focusOverD_(focusDistance / d_) {
  if (spp_ == 1 && lensRadius_ == 0) {
    // x = j + ½ is exactly what samplePosition gives at 1 spp, so the tables hold the very
    // values rayAt computes.
    // Three more entries each way: tail lanes of a 4-wide block past the edge get their
    // (masked) rays from the same formula too.
    double v;
    uCol_.resize(size_t(width_) + 3);
    vRow_.resize(size_t(height_) + 3);
    for (int j = 0; j < width_ + 3; ++j) rasterToPlane(j + 0.5, 0.5, uCol_[size_t(j)], v);
    for (int i = 0; i < height_ + 3; ++i) rasterToPlane(0.5, i + 0.5, v, vRow_[size_t(i)]);
  }
}

void PerspectiveCamera::generate(const PacketRequest& req, RayLanes& out, int* valid) const {
  if (uCol_.empty())
    PacketCamera::generate(req, out, valid);
  else
    generatePinholeCentres(req, out, valid);
}

void PerspectiveCamera::generatePinholeCentres(const PacketRequest& req, RayLanes& out,
                                               int* valid) const {
  const int lanes = req.blockW * req.blockH;
  alignas(64) double uLane[16], vLane[16];
  for (int k = 0; k < lanes; ++k) {
    const int i = req.y0 + k / req.blockW, j = req.x0 + k % req.blockW;
    valid[k] = i < height_ && j < width_ ? -1 : 0;
    uLane[k] = uCol_[size_t(std::min(j, width_ + 2))];
    vLane[k] = vRow_[size_t(std::min(i, height_ + 2))];
  }
  // rayAt's pinhole branch term by term: (u·U + v·V) − d·W, times 1 / its length.
  // Computed into local arrays (no aliasing, so the loop vectorises), then stored.
  const glm::dvec3 U = frame_.u, V = frame_.v, dW = d_ * frame_.w;
  alignas(64) float dx[16], dy[16], dz[16];
  for (int k = 0; k < lanes; ++k) {
    const double px = (uLane[k] * U.x + vLane[k] * V.x) - dW.x;
    const double py = (uLane[k] * U.y + vLane[k] * V.y) - dW.y;
    const double pz = (uLane[k] * U.z + vLane[k] * V.z) - dW.z;
    const double invLen = 1.0 / std::sqrt((px * px + py * py) + pz * pz);
    dx[k] = float(px * invLen);
    dy[k] = float(py * invLen);
    dz[k] = float(pz * invLen);
  }
  const float ox = float(renderEyeD_.x), oy = float(renderEyeD_.y), oz = float(renderEyeD_.z);
  const float inf = std::numeric_limits<float>::infinity();
  for (int k = 0; k < lanes; ++k) {
    out.dirX[k] = dx[k];
    out.dirY[k] = dy[k];
    out.dirZ[k] = dz[k];
    out.orgX[k] = ox;
    out.orgY[k] = oy;
    out.orgZ[k] = oz;
    out.tnear[k] = 0.0f;
    out.tfar[k] = inf;
    out.time[k] = 0.0f;
    out.mask[k] = 0xFFFFFFFFu;
    out.id[k] = unsigned(k);
    out.flags[k] = 0;
  }
}

std::optional<glm::dvec2> PerspectiveCamera::project(const glm::dvec3& worldPoint) const {
  const glm::dvec3 p = worldPoint - frame_.e;
  const double depth = -glm::dot(p, frame_.w);
  if (!(depth > 0)) return std::nullopt;
  return planeToRaster(d_ * glm::dot(p, frame_.u) / depth, d_ * glm::dot(p, frame_.v) / depth);
}

ViewVolume PerspectiveCamera::viewVolume(double nearDist, double farDist) const {
  // Every ray is L + (z / f)·(F − L) at depth z, L on the lens (|Lx|, |Ly| <= r) and F in the
  // window scaled to depth f, so x lies in [uLo·z/d − h(z), uHi·z/d + h(z)] with
  // h(z) = r·|1 − z/f|. h is convex, so on [near, far] it lies below its chord; for an
  // infinite far the line r·(z/f − 1) + 2r·max(0, 1 − near/f) bounds it.
  const double r = lensRadius_, f = focusDistance_;
  ViewVolume::Linear h;
  if (r > 0) {
    auto hAt = [&](double z) { return r * std::abs(1.0 - z / f); };
    if (!std::isfinite(farDist)) {
      h.b = r / f;
      h.a = -r + 2.0 * r * std::max(0.0, 1.0 - nearDist / f);
    } else if (farDist > nearDist) {
      h.b = (hAt(farDist) - hAt(nearDist)) / (farDist - nearDist);
      h.a = hAt(nearDist) - h.b * nearDist;
      // Rounding of the chord must not cut into h at the ends.
      h.a += 1e-12 * (std::abs(h.a) + std::abs(h.b) * farDist);
    } else {
      h.a = hAt(nearDist);
    }
  }
  const ViewVolume::Linear xLo{-h.a, uLo() / d_ - h.b}, xHi{h.a, uHi() / d_ + h.b};
  const ViewVolume::Linear yLo{-h.a, vLo() / d_ - h.b}, yHi{h.a, vHi() / d_ + h.b};
  return ViewVolume::planar(r > 0 ? ViewVolume::Kind::ShearedFrustum : ViewVolume::Kind::Frustum,
                            frame_.e, frame_.u, frame_.v, frame_.w, nearDist, farDist, xLo, xHi,
                            yLo, yHi);
}

glm::dmat4 PerspectiveCamera::ndcFromCamera() const {
  // x_ndc = (d x / −z) / vw − sx + ½ and y_ndc = ½ − ((d y / −z) / vh − sy), after dividing
  // by w = −z; the third row gives z_ndc = 1 / Z. GLM: m[column][row].
  glm::dmat4 m(0.0);
  m[0][0] = d_ / vw_;
  m[2][0] = shift_.x - 0.5;
  m[1][1] = -d_ / vh_;
  m[2][1] = -(0.5 + shift_.y);
  m[3][2] = 1.0;
  m[2][3] = -1.0;
  return m;
}

void PerspectiveCamera::describeExtra(CameraDescription& c) const {
  c.extra.emplace_back("fov_x_deg", cat(2.0 * std::atan(0.5 * vw_ / d_) * kDegPerRad));
  c.extra.emplace_back("fov_y_deg", cat(2.0 * std::atan(0.5 * vh_ / d_) * kDegPerRad));
  if (lensRadius_ > 0 || type_ == "thinlens") {
    c.extra.emplace_back("aperture_radius", cat(lensRadius_));
    c.extra.emplace_back("focus_distance", cat(focusDistance_));
  }
}

std::unique_ptr<FrameCamera> makePerspectiveCamera(const CameraParams& p,
                                                   const glm::dvec3& renderOrigin) {
  if (p.apertureRadius != 0)
    throw Error("camera: --aperture needs --camera thinlens (perspective is a pinhole)");
  return std::make_unique<PerspectiveCamera>(p, renderOrigin, "perspective", 0.0, 1.0);
}

}  // namespace aperture
