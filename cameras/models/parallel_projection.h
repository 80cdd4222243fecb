#pragma once
// Parallel projections: orthographic (direction −W) and oblique (a common direction that
// differs from −W). Origins lie on the image plane through the eye: e + u·U + v·V.
#include "cameras/models/base.h"

namespace aperture {

/// A parallel camera with one unit direction for every ray. The viewport (vw, vh) is in
/// world units and must be given explicitly (params.viewport): a field of view does not
/// define a parallel projection, so fov or focal length alone is an Error.
class ParallelCamera final : public PacketCamera<ParallelCamera> {
 public:
  /// worldDir: the common unit direction (world space), at less than 89° from −W.
  ParallelCamera(const CameraParams& p, const glm::dvec3& renderOrigin, const char* typeName,
                 const glm::dvec3& worldDir);

  bool usesLens() const { return false; }
  bool rayAt(double x, double y, double, double, glm::dvec3& org, glm::dvec3& dir) const {
    double u, v;
    planeFromRaster(x, y, u, v);
    org = renderEyeD_ + u * frame_.u + v * frame_.v;
    dir = dir_;
    return true;
  }

  /// Rays through pixel centres (every sample at 1 spp, the centre ray at any spp) in the
  /// frame loop's block shapes take a vector kernel that computes exactly rayAt()'s
  /// expressions; everything else the shared packet loop.
  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override;

  std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const override;
  ViewVolume viewVolume(double nearDist, double farDist) const override;
  const glm::dvec3& direction() const { return dir_; }

 protected:
  std::optional<glm::dmat4> planeFromCamera() const override;
  void describeExtra(CameraDescription& c) const override;

 private:
  glm::dvec3 dir_;
  double shearU_ = 0, shearV_ = 0;  ///< U and V movement per unit of depth along −W
  PixelCentreTable centres_;        ///< u, v of the pixel centres: the centre-ray kernel's
};

}  // namespace aperture
