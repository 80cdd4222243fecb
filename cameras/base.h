#pragma once
// Shared state of the frame-based cameras: frame, image plane, render origin, pixel mapping,
// and the packet loop every model uses (PacketCamera).
#include <cstring>
#include <limits>
#include <optional>
#include <string>

#include "cameras/frame.h"
#include "cameras/image_window.h"
#include "cameras/params.h"
#include "cameras/view_volume.h"
#include "core/camera.h"

namespace aperture {

/// Image-plane distance and viewport from whichever convention the parameters use:
/// explicit d + viewport, else focal length + sensor, else fov on fovAxis at d (default d = 1,
/// default fov 45° vertical). Focal length + sensor: the sensor spans the image dimension
/// sensorFit chooses, as Blender's sensor_fit (viewportOfSensor, cameras/conventions.h).
/// Throws Error for d <= 0, viewport <= 0, non-finite values or fov outside (0°, 180°).
void resolveImagePlane(const CameraParams& p, double& d, double& vw, double& vh);

/// Builds the frame from eye + at / dir + up (errors as CameraFrame).
CameraFrame frameFromParams(const CameraParams& p);

/// Base for cameras defined by a frame and an image plane. Precomputes the render-space eye,
/// the axes and the effective shift (user shift plus the architectural tilt shift).
class CameraBase : public Camera {
 public:
  CameraBase(const CameraParams& p, const glm::dvec3& renderOrigin, const char* typeName);

  glm::vec3 renderEye() const override { return renderEye_; }
  glm::vec3 viewAxis() const override { return viewAxis_; }
  bool stochastic() const override { return spp_ > 1; }
  CameraDescription describe() const override;

  /// The ray through raster position (x, y) (column, row, continuous; pixel (i, j) centre at
  /// (j + ½, i + ½)) with lens sample (lensX, lensY) in [0, 1)² (ignored by pinhole and
  /// parallel models). Writes the origin in render space and the unit direction, both in
  /// double before the one rounding to float that generate() applies. Returns false where
  /// the position has no ray (outside a fisheye's circle); the outputs are then still finite.
  virtual bool ray(double x, double y, double lensX, double lensY, glm::dvec3& renderOrg,
                   glm::dvec3& dir) const = 0;

  /// Raster position (x, y) (same convention as ray()) of a world point, or nothing when the
  /// point has no image position (behind a pinhole, behind a parallel camera's image plane,
  /// outside a fisheye's field). The position may lie outside [0, W] x [0, H]. Thin lens:
  /// the centre of the circle of confusion (the pinhole projection).
  virtual std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const = 0;

  /// The view volume between nearDist and farDist (see view_volume.h for their meaning).
  virtual ViewVolume viewVolume(double nearDist, double farDist) const = 0;

  /// The image window: raster size, viewport and effective shift (cameras/image_window.h,
  /// the one owner of the shift formula).
  ImageWindow window() const { return {width_, height_, vw_, vh_, shift_}; }
  /// Image-plane coordinates (u, v) of a raster position, shift included (ImageWindow).
  void rasterToPlane(double x, double y, double& u, double& v) const {
    const ImageWindow w = window();
    u = w.u(x);
    v = w.v(y);
  }
  /// Raster position of pixel (row i, column j), sample s: the pixel centre (j + ½, i + ½)
  /// for spp 1 and for s = PacketRequest::kCentreRay, else stratified.
  void samplePosition(int i, int j, int s, double& x, double& y) const;
  /// Lens sample in [0, 1)² of pixel (i, j), sample s: stratified over the spp samples like
  /// the pixel positions, with the strata paired through a per-pixel permutation so lens and
  /// pixel positions are not correlated. The lens centre (½, ½) for spp 1 and for
  /// s = PacketRequest::kCentreRay. Depends on (i, j, s) only.
  void lensSample(int i, int j, int s, double& lensX, double& lensY) const;

  const CameraFrame& frame() const { return frame_; }
  const CameraParams& params() const { return params_; }
  double d() const { return d_; }
  double vw() const { return vw_; }
  double vh() const { return vh_; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// Effective shift in viewport units (params.shift or params.blenderShift converted, plus
  /// the architectural tilt shift).
  const glm::dvec2& shift() const { return shift_; }
  /// The image window on the plane at distance d: u in [uLo, uHi], v in [vLo, vHi].
  double uLo() const { return window().uLo(); }
  double uHi() const { return window().uHi(); }
  double vLo() const { return window().vLo(); }
  double vHi() const { return window().vHi(); }
  /// Raster position of image-plane coordinates (inverse of rasterToPlane).
  glm::dvec2 planeToRaster(double u, double v) const { return window().raster(u, v); }
  /// The one NDC map of the planar cameras, as a matrix on homogeneous image-plane coordinates
  /// (u, v, z, w): OpenEXR's NDC x = (u − uLo) / vw, y = (vHi − v) / vh, so the window's
  /// top-left corner (uLo, vHi) goes to (0, 0) and its bottom-right corner (uHi, vLo) to
  /// (1, 1); NDC · (W, H) is planeToRaster. z and w pass through. GLM column vectors.
  glm::dmat4 ndcFromPlane() const;

 protected:
  /// The model's projection from OpenEXR camera space (CameraDescription::cameraFromWorld) to
  /// homogeneous image-plane coordinates (u, v, z', w): u / w and v / w are the (u, v) of
  /// rasterToPlane. Nothing where no 4x4 matrix expresses the projection (panoramas); then
  /// describe() leaves ndcFromWorld empty.
  virtual std::optional<glm::dmat4> planeFromCamera() const { return std::nullopt; }
  /// Model-specific parts of describe(): the (name, value) pairs of CameraDescription::extra,
  /// and where they differ from the planar defaults, the screen window, the pixel aspect ratio
  /// and the panorama projection.
  virtual void describeExtra(CameraDescription&) const {}
  /// Throws Error naming the model if a shift, a Blender shift, the architectural flag or a
  /// clip was given (parameters of the perspective and thin-lens models only).
  void rejectShift() const;

  CameraParams params_;
  CameraFrame frame_;
  glm::dvec3 renderOrigin_;
  glm::dvec3 renderEyeD_;  ///< e − renderOrigin, double
  double d_ = 1, vw_ = 1, vh_ = 1;
  glm::dvec2 shift_{0.0};
  double tiltRad_ = 0;  ///< architectural: the view direction's angle above the horizon
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

/// Writes the kLanes lanes of a block of rays from one origin (double, rounded once) with
/// directions already rounded to float, and the fixed fields as setLane. The fast paths of
/// the perspective and calibrated cameras share it.
template <int kLanes>
inline void writeBlockLanes(RayLanes& out, const glm::dvec3& org, const float* dx, const float* dy,
                            const float* dz) {
  // Each lane array is filled whole by a fixed-size copy: GCC does not vectorise one loop over
  // twelve output streams (pointer spills, scalar stores), but a 4 kLanes-byte memcpy is a few
  // vector moves.
  const float ex = float(org.x), ey = float(org.y), ez = float(org.z);
  const float inf = std::numeric_limits<float>::infinity();
  alignas(64) float fill[kLanes];
  alignas(64) unsigned word[kLanes];
  constexpr size_t kBytes = sizeof(float) * kLanes;
  std::memcpy(out.dirX, dx, kBytes);
  std::memcpy(out.dirY, dy, kBytes);
  std::memcpy(out.dirZ, dz, kBytes);
  for (float& f : fill) f = ex;
  std::memcpy(out.orgX, fill, kBytes);
  for (float& f : fill) f = ey;
  std::memcpy(out.orgY, fill, kBytes);
  for (float& f : fill) f = ez;
  std::memcpy(out.orgZ, fill, kBytes);
  for (float& f : fill) f = inf;
  std::memcpy(out.tfar, fill, kBytes);
  for (float& f : fill) f = 0.0f;
  std::memcpy(out.tnear, fill, kBytes);
  std::memcpy(out.time, fill, kBytes);
  for (unsigned& w : word) w = 0;
  std::memcpy(out.flags, word, kBytes);
  for (unsigned& w : word) w = 0xFFFFFFFFu;
  std::memcpy(out.mask, word, kBytes);
  for (int k = 0; k < kLanes; ++k) word[k] = unsigned(k);
  std::memcpy(out.id, word, kBytes);
}

/// The packet loop, shared by every model: Derived provides an inline
/// `bool rayAt(x, y, lensX, lensY, org, dir) const` and `bool usesLens() const`. generate()
/// and the scalar ray() both call rayAt, so packets equal the scalar path exactly.
template <class Derived>
class PacketCamera : public CameraBase {
 public:
  using CameraBase::CameraBase;

  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    const Derived& self = static_cast<const Derived&>(*this);
    const bool lens = self.usesLens();
    for (int k = 0; k < req.lanes(); ++k) {
      const LanePixel px = req.pixel(k);
      double x, y, lensX = 0.5, lensY = 0.5;
      samplePosition(px.row, px.column, req.sample, x, y);
      if (lens) lensSample(px.row, px.column, req.sample, lensX, lensY);
      glm::dvec3 org, dir;
      const bool hasRay = self.rayAt(x, y, lensX, lensY, org, dir);
      valid[k] = (hasRay && px.inImage(width_, height_)) ? -1 : 0;
      setLane(out, k, org, dir);
    }
  }

  bool ray(double x, double y, double lensX, double lensY, glm::dvec3& renderOrg,
           glm::dvec3& dir) const override {
    return static_cast<const Derived&>(*this).rayAt(x, y, lensX, lensY, renderOrg, dir);
  }
};

}  // namespace aperture
