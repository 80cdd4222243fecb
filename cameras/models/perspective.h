#pragma once
// The perspective camera of the lecture, with shift, the architectural mode and an optional
// thin lens (the thin-lens camera is this class with a lens radius; see thinlens.cpp).
#include "cameras/models/base.h"
#include "cameras/models/thinlens.h"

namespace aperture {

/// What the pinhole kernel reads besides the pixel-centre table, taken once in double by the
/// camera (perspective.cpp).
struct PinholeConstants {
  glm::dvec3 u, v, dW;  ///< U, V and d·W
  glm::dvec3 eye;       ///< render-space eye
  int width = 0, height = 0;
};

/// Pinhole: origin e, direction normalize(u·U + v·V − d·W).
/// Thin lens (lensRadius > 0): lens point L = r·(a·U + b·V) with (a, b) the concentric map
/// of the lens sample; origin e + L, direction normalize((f / d)·(u·U + v·V − d·W) − L), i.e.
/// through the point the pinhole ray reaches at depth f (the in-focus plane). With
/// lensRadius 0 the pinhole branch runs, so aperture 0 equals the pinhole bit for bit.
class PerspectiveCamera final : public PacketCamera<PerspectiveCamera> {
 public:
  /// lensRadius and focusDistance in scene units (lensRadius 0: pinhole).
  PerspectiveCamera(const CameraParams& p, const glm::dvec3& renderOrigin, const char* typeName,
                    double lensRadius, double focusDistance);

  bool usesLens() const { return lensRadius_ > 0; }
  bool rayAt(double x, double y, double lensX, double lensY, glm::dvec3& org,
             glm::dvec3& dir) const {
    double u, v;
    planeFromRaster(x, y, u, v);
    const glm::dvec3 pinhole = u * frame_.u + v * frame_.v - d_ * frame_.w;
    if (lensRadius_ > 0) {
      double a, b;
      concentricDisk(lensX, lensY, a, b);
      const glm::dvec3 lens = lensRadius_ * (a * frame_.u + b * frame_.v);
      const glm::dvec3 toFocus = pinhole * focusOverD_ - lens;
      org = renderEyeD_ + lens;
      dir = toFocus / glm::length(toFocus);
    } else {
      org = renderEyeD_;
      // One reciprocal, three products (as pinholeCentreRays, which must match it).
      dir = pinhole * (1.0 / std::sqrt((pinhole.x * pinhole.x + pinhole.y * pinhole.y) +
                                       pinhole.z * pinhole.z));
    }
    return true;
  }

  /// Pinhole rays through pixel centres (every sample at 1 spp, the centre ray at any spp)
  /// take a vectorised SoA path that computes exactly rayAt()'s expressions; everything else
  /// the shared packet loop.
  /// With a clip, every lane then gets tnear = near / cos and tfar = far / cos (cos: the
  /// direction's cosine with the view axis), so depth, not distance, is clipped.
  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override;

  bool stochastic() const override { return spp_ > 1 || lensRadius_ > 0; }
  /// The eye, for a pinhole without clip planes (a lens spreads the origins, a clip sets tnear).
  std::optional<glm::vec3> sharedRayOrigin() const override {
    if (lensRadius_ > 0 || clip_) return std::nullopt;
    return renderEye_;
  }
  std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const override;
  ViewVolume viewVolume(double nearDist, double farDist) const override;
  double lensRadius() const { return lensRadius_; }
  double focusDistance() const { return focusDistance_; }

 protected:
  std::optional<glm::dmat4> planeFromCamera() const override;
  void describeExtra(CameraDescription& c) const override;

 private:
  void generateUnclipped(const PacketRequest& req, RayLanes& out, int* valid) const;
  /// Sets tnear and tfar of lanes [0, lanes) from the clip depths.
  void clipLanes(RayLanes& out, int lanes) const;

  double lensRadius_ = 0, focusDistance_ = 1, focusOverD_ = 1;
  std::optional<glm::dvec2> clip_;  ///< near, far planar depth (CameraParams::clip)
  /// 1 spp without a lens: rays through pixel centres, the vectorised path.
  bool pinholeCentres_ = false;
  PixelCentreTable centres_;  ///< u, v of the pixel centres: the pinhole and thin-lens kernels'
  PinholeConstants
      pinhole_;  ///< the pinhole kernel's frame, eye and size; d·W also the thin lens's
};

}  // namespace aperture
