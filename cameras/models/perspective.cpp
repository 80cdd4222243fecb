// Perspective camera of the lecture: origin e, direction u·U + v·V − d·W, normalised; the
// window may be shifted (params.shift, or the tilt of the architectural mode).
#include "cameras/models/perspective.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cameras/models/camera_models.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "core/util/vector_kernel.h"

namespace aperture {

PerspectiveCamera::PerspectiveCamera(const CameraParams& p, const glm::dvec3& renderOrigin,
                                     const char* typeName, double lensRadius, double focusDistance)
    : PacketCamera(p, renderOrigin, typeName),
      lensRadius_(lensRadius),
      focusDistance_(focusDistance),
      focusOverD_(focusDistance / d_),
      clip_(p.clip) {
  pinholeCentres_ = spp_ == 1 && lensRadius_ == 0;
  centres_ = PixelCentreTable(window());
  pinhole_ = {frame_.u, frame_.v, d_ * frame_.w, renderEyeD_, width_, height_};
  // The range of each end (finite, >= 0) is the clip spec's, checked by makeCamera; their
  // order is not a range.
  if (clip_ && !(clip_->x < clip_->y))
    throw Error(cat("camera: clip ", clip_->x, ",", clip_->y,
                    ": near must be less than far (planar depths, scene units)"));
}

namespace {

/// The pinhole rays of the kBW x kBH block at (x0, y0): rayAt's pinhole branch term by term,
/// (u·U + v·V) − d·W times 1 / its length, in double, rounded once. A per-ISA kernel
/// (core/util/vector_kernel.h): no divide but the reciprocal, constant trip counts, vector stores.
template <int kBW, int kBH>
void pinholeCentreRays(const PinholeConstants& in, const PixelCentreTable& centres, int x0, int y0,
                       RayLanes& out, int* valid) {
  constexpr int kLanes = kBW * kBH;
  const double* __restrict columnU = centres.u.data() + x0;
  const double* __restrict rowV = centres.v.data() + y0;
  const glm::dvec3 U = in.u, V = in.v, dW = in.dW;
  alignas(64) double us[kLanes], vs[kLanes];
  spreadOverLanes<kBW, kBH>(columnU, rowV, us, vs);
  alignas(64) float dx[kLanes], dy[kLanes], dz[kLanes];
  APERTURE_LANE_LOOP
  for (int k = 0; k < kLanes; ++k) {
    const double u = us[k], v = vs[k];
    const double px = (u * U.x + v * V.x) - dW.x;
    const double py = (u * U.y + v * V.y) - dW.y;
    const double pz = (u * U.z + v * V.z) - dW.z;
    const double invLen = 1.0 / std::sqrt((px * px + py * py) + pz * pz);
    dx[k] = float(px * invLen);
    dy[k] = float(py * invLen);
    dz[k] = float(pz * invLen);
  }
  writeBlockLanesFromOrigin<kLanes>(out, in.eye, dx, dy, dz);
  writeBlockInImage<kBW, kBH>(x0, y0, in.width, in.height, valid);
}

}  // namespace

void PerspectiveCamera::generate(const PacketRequest& req, RayLanes& out, int* valid) const {
  generateUnclipped(req, out, valid);
  if (clip_) clipLanes(out, req.lanes());
}

void PerspectiveCamera::generateUnclipped(const PacketRequest& req, RayLanes& out,
                                          int* valid) const {
  // Pinhole rays through pixel centres: every sample at spp 1, the centre ray at any spp.
  if (pinholeCentres_ || (req.centreRay() && lensRadius_ == 0)) {
    const bool done = withBlockShape(req.blockW, req.blockH, [&](auto bw, auto bh) {
      runKernel<&pinholeCentreRays<decltype(bw)::value, decltype(bh)::value>>(
          pinhole_, centres_, req.x0, req.y0, out, valid);
    });
    if (done) return;
  }
  // Thin-lens rays through pixel centres and the lens centre: thinlens.cpp's kernel.
  if (lensRadius_ > 0 && (spp_ == 1 || req.centreRay())) {
    const glm::dvec3 lens = lensRadius_ * (0.0 * frame_.u + 0.0 * frame_.v);  // rayAt's L
    const ThinLensCentres c{
        centres_.u.data(), centres_.v.data(), width_,      height_, frame_.u,
        frame_.v,          pinhole_.dW,       focusOverD_, lens,    renderEyeD_ + lens};
    if (generateThinLensCentres(c, req, out, valid)) return;
  }
  PacketCamera::generate(req, out, valid);
}

void PerspectiveCamera::clipLanes(RayLanes& out, int lanes) const {
  // Every origin lies on the plane through e perpendicular to the axis (the eye, or a lens
  // point), so a ray reaches depth z at t = z / cos, cos its direction's cosine with the axis:
  // the clip planes are planes of constant depth, as Blender's clip_start and clip_end. The
  // cosine is taken of the float direction Embree traces. Perspective and thin-lens rays
  // always point forwards (cos > 0); the floor only keeps invalid lanes finite.
  const glm::dvec3 axis = -frame_.w;
  for (int k = 0; k < lanes; ++k) {
    const double cosine =
        double(out.dirX[k]) * axis.x + double(out.dirY[k]) * axis.y + double(out.dirZ[k]) * axis.z;
    const double c = std::max(cosine, 1e-9);
    out.tnear[k] = float(clip_->x / c);
    out.tfar[k] = float(clip_->y / c);
  }
}

std::optional<glm::dvec2> PerspectiveCamera::project(const glm::dvec3& worldPoint) const {
  const glm::dvec3 p = worldPoint - frame_.e;
  const double depth = -glm::dot(p, frame_.w);
  if (!(depth > 0)) return std::nullopt;
  return rasterFromPlane(d_ * glm::dot(p, frame_.u) / depth, d_ * glm::dot(p, frame_.v) / depth);
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

std::optional<glm::dmat4> PerspectiveCamera::planeFromCamera() const {
  // Camera space (x, y, z), z the depth: u = d·x / z, v = d·y / z after dividing by w = z;
  // z' = 1, so NDC z is 1 / Z. GLM: m[column][row].
  glm::dmat4 m(0.0);
  m[0][0] = d_;
  m[1][1] = d_;
  m[3][2] = 1.0;
  m[2][3] = 1.0;
  return m;
}

void PerspectiveCamera::describeExtra(CameraDescription& c) const {
  // OpenEXR's screen window: the image window [uLo, uHi] x [vLo, vHi] at distance d, scaled to
  // the plane z = 1, in camera-space x (right) and y (up). (The Technical Introduction calls
  // +x the camera's "left"; the worldToCamera definition, followed here, says "right".)
  c.screenWindowCenter = glm::dvec2(0.5 * (uLo() + uHi()), 0.5 * (vLo() + vHi())) / d_;
  c.screenWindowWidth = vw_ / d_;
  c.extra.emplace_back("fov_x_deg", cat(2.0 * std::atan(0.5 * vw_ / d_) * kDegPerRad));
  c.extra.emplace_back("fov_y_deg", cat(2.0 * std::atan(0.5 * vh_ / d_) * kDegPerRad));
  if (clip_) c.extra.emplace_back("clip", cat(clip_->x, ",", clip_->y));
  if (lensRadius_ > 0 || type_ == "thinlens") {
    c.extra.emplace_back("aperture_radius", cat(lensRadius_));
    c.extra.emplace_back("focus_distance", cat(focusDistance_));
  }
}

namespace {

const ParamSpec kClip =
    ParamSpec("clip", ParamKind::Vec2, fieldAccess<&CameraParams::clip>())
        .withUnit("scene units")
        .withHelp(
            "Near,far clipping: planar depths along the view axis (Blender's clip_start, "
            "clip_end); near < far")
        .withDefaultRule("none (no clipping)")
        .withRange(ParamRange::atLeast(0.0));

std::unique_ptr<CameraBase> makePerspectiveCamera(const CameraParams& p,
                                                  const glm::dvec3& renderOrigin) {
  if (p.apertureRadius != 0)
    throw Error("camera: --aperture needs --camera thinlens (perspective is a pinhole)");
  return std::make_unique<PerspectiveCamera>(p, renderOrigin, "perspective", 0.0, 1.0);
}

}  // namespace

const std::vector<const ParamSpec*>& perspectiveParamSpecs() {
  static const std::vector<const ParamSpec*> v =
      joinParamSpecs({perspectiveWindowParamSpecs(), {&kClip}});
  return v;
}

const CameraModel& perspectiveModel() {
  static const CameraModel m{"perspective",
                             "pinhole: rays from e through the image plane at distance d",
                             makePerspectiveCamera,
                             joinParamSpecs({commonParamSpecs(),
                                             {&distanceParamSpec(), &viewportParamSpec()},
                                             perspectiveParamSpecs()})};
  return m;
}

}  // namespace aperture
