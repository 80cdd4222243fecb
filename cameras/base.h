#pragma once
// Shared state of the frame-based cameras: frame, image plane, render origin, pixel mapping.
#include <limits>
#include <string>

#include "cameras/frame.h"
#include "cameras/params.h"
#include "core/camera.h"

namespace aperture {

/// Image-plane distance and viewport from whichever convention the parameters use:
/// explicit d + viewport, else focal length + sensor (d = focal length in mm scaled to 1),
/// else fov on fovAxis at d (default d = 1, default fov 45° vertical). Throws Error for
/// d <= 0, viewport <= 0, non-finite values or fov outside (0°, 180°).
void resolveImagePlane(const CameraParams& p, double& d, double& vw, double& vh);

/// Builds the frame from eye + at / dir + up (errors as CameraFrame).
CameraFrame frameFromParams(const CameraParams& p);

/// Base for cameras defined by a frame and an image plane. Precomputes the render-space eye
/// and axes; subclasses implement generate().
class FrameCamera : public Camera {
 public:
  FrameCamera(const CameraParams& p, const glm::dvec3& renderOrigin, const char* typeName);

  glm::vec3 renderEye() const override { return renderEye_; }
  glm::vec3 viewAxis() const override { return viewAxis_; }
  bool stochastic() const override { return spp_ > 1; }
  CameraDescription describe() const override;

  /// Image-plane coordinates (u, v) of a raster position (column x, row y, continuous; pixel
  /// (i, j) centre at (j + 0.5, i + 0.5)): u = (x / W − ½)·vw, v = −(y / H − ½)·vh.
  void rasterToPlane(double x, double y, double& u, double& v) const {
    u = (x / width_ - 0.5) * vw_;
    v = -(y / height_ - 0.5) * vh_;
  }
  /// Raster position of pixel (row i, column j), sample s: centre for spp 1, else stratified.
  void samplePosition(int i, int j, int s, double& x, double& y) const;

  const CameraFrame& frame() const { return frame_; }
  double d() const { return d_; }
  double vw() const { return vw_; }
  double vh() const { return vh_; }

 protected:
  /// ndcFromCamera for describe(); identity for non-linear projections.
  virtual glm::dmat4 ndcFromCamera() const { return glm::dmat4(1.0); }

  CameraParams params_;
  CameraFrame frame_;
  glm::dvec3 renderOrigin_;
  double d_ = 1, vw_ = 1, vh_ = 1;
  int width_ = 1, height_ = 1, spp_ = 1;
  glm::vec3 renderEye_, viewAxis_;
  std::string type_;
};

/// Writes one lane: origin/direction (double, rounded once to float) and the fixed fields.
inline void setLane(RayLanes& out, int k, const glm::dvec3& org, const glm::dvec3& dir) {
  out.orgX[k] = float(org.x);
  out.orgY[k] = float(org.y);
  out.orgZ[k] = float(org.z);
  out.dirX[k] = float(dir.x);
  out.dirY[k] = float(dir.y);
  out.dirZ[k] = float(dir.z);
  out.tnear[k] = 0.0f;
  out.tfar[k] = std::numeric_limits<float>::infinity();
  out.time[k] = 0.0f;
  out.mask[k] = 0xFFFFFFFFu;
  out.id[k] = unsigned(k);
  out.flags[k] = 0;
}

}  // namespace aperture
