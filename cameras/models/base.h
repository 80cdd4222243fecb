#pragma once
// Shared state of the frame-based cameras: frame, image plane, render origin, pixel mapping,
// and the packet loop every model uses (PacketCamera).
#include <cstring>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>

#include "cameras/geometry/frame.h"
#include "cameras/geometry/view_volume.h"
#include "cameras/schema/image_window.h"
#include "cameras/schema/param_schema.h"
#include "cameras/schema/params.h"
#include "core/engine/camera.h"
#include "core/util/vector_kernel.h"

namespace aperture {

/// The parameters CameraBase reads, declared in base.cpp: type, size, spp, eye, at,
/// dir, up (every model reads them).
const std::vector<const ParamSpec*>& commonParamSpecs();
/// The image-plane window of the planar models: d and viewport.
const ParamSpec& distanceParamSpec();
const ParamSpec& viewportParamSpec();
/// The window of the perspective models: fov, fov_axis, focal_length, sensor, sensor_fit,
/// shift, blender_shift, architectural.
const std::vector<const ParamSpec*>& perspectiveWindowParamSpecs();
/// `fov`, whose default (defaultAs<double>()) applies when no viewport and no focal length is
/// given.
const ParamSpec& fovParamSpec();
/// The concatenation of spec lists (a model's parameters from shared groups).
std::vector<const ParamSpec*> joinParamSpecs(
    std::initializer_list<std::vector<const ParamSpec*>> groups);

/// Image-plane distance and viewport from whichever convention the parameters use:
/// explicit d + viewport, else focal length + sensor, else fov on fovAxis at d (d and fov not
/// given: their specs' defaults). Focal length + sensor: the sensor spans the image dimension
/// sensorFit chooses, as Blender's sensor_fit (viewportOfSensor, cameras/schema/conventions.h).
/// Throws Error for viewport <= 0 and non-finite values; the ranges of d and fov are the
/// specs' (checked by makeCamera).
void resolveImagePlane(const CameraParams& p, double& d, double& vw, double& vh);

/// Builds the frame from eye + at / dir + up (errors as CameraFrame). A model posed otherwise
/// (the calibrated camera's matrices) passes its own frame to CameraBase.
CameraFrame frameFromParams(const CameraParams& p);

/// Base for cameras defined by a frame and an image plane. Precomputes the render-space eye,
/// the axes and the effective shift (user shift plus the architectural tilt shift).
class CameraBase : public Camera {
 public:
  /// The frame from eye / at / dir / up (frameFromParams).
  CameraBase(const CameraParams& p, const glm::dvec3& renderOrigin, const char* typeName);
  /// The frame given (a model with a pose of its own).
  CameraBase(const CameraParams& p, const CameraFrame& frame, const glm::dvec3& renderOrigin,
             const char* typeName);

  glm::vec3 renderEye() const override { return renderEye_; }
  glm::vec3 viewAxis() const override { return viewAxis_; }
  bool stochastic() const override { return spp_ > 1; }
  CameraDescription describe() const override;
  CameraDescription describeWithoutCounts() const override;
  WorldView worldView() const override { return {frame_.e, frame_.w}; }

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
  std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const override = 0;
  /// ray() at the lens centre (½, ½): the centre ray of PacketRequest::kCentreRay.
  bool centreRayAt(double x, double y, glm::dvec3& renderOrg, glm::dvec3& dir) const override {
    return ray(x, y, 0.5, 0.5, renderOrg, dir);
  }

  /// The view volume between nearDist and farDist (see view_volume.h for their meaning).
  virtual ViewVolume viewVolume(double nearDist, double farDist) const = 0;

  /// The image window: raster size, viewport and effective shift (cameras/schema/image_window.h,
  /// the one owner of the shift formula).
  ImageWindow window() const { return {width_, height_, vw_, vh_, shift_}; }
  /// Image-plane coordinates (u, v) of a raster position, shift included (ImageWindow).
  void planeFromRaster(double x, double y, double& u, double& v) const {
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
  /// Raster position of image-plane coordinates (inverse of planeFromRaster).
  glm::dvec2 rasterFromPlane(double u, double v) const { return window().raster(u, v); }
  /// The one NDC map of the planar cameras, as a matrix on homogeneous image-plane coordinates
  /// (u, v, z, w): OpenEXR's NDC x = (u − uLo) / vw, y = (vHi − v) / vh, so the window's
  /// top-left corner (uLo, vHi) goes to (0, 0) and its bottom-right corner (uHi, vLo) to
  /// (1, 1); NDC · (W, H) is rasterFromPlane. z and w pass through. GLM column vectors.
  glm::dmat4 ndcFromPlane() const;

 protected:
  /// The model's projection from OpenEXR camera space (CameraDescription::cameraFromWorld) to
  /// homogeneous image-plane coordinates (u, v, z', w): u / w and v / w are the (u, v) of
  /// planeFromRaster. Nothing where no 4x4 matrix expresses the projection (panoramas); then
  /// describe() leaves ndcFromWorld empty.
  virtual std::optional<glm::dmat4> planeFromCamera() const { return std::nullopt; }
  /// Model-specific parts of describe(): the (name, value) pairs of CameraDescription::extra,
  /// and where they differ from the planar defaults, the screen window, the pixel aspect ratio
  /// and the panorama projection.
  virtual void describeExtra(CameraDescription&) const {}
  /// The extras describe() counts over the image (isCountedExtra), appended after the others.
  virtual void describeCounts(CameraDescription&) const {}
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

/// The stores of a block of kLanes rays: origins and directions already rounded to float,
/// and the fixed fields as setLane. Every pointer is a restrict *parameter*: GCC honours
/// restrict on parameters (inlined too), but not on local copies such as writeBlockLanes
/// makes; there it needs more run-time alias checks than it allows (10) and leaves the loop
/// scalar.
template <int kLanes>
inline void storeBlockLanes(float* __restrict orgX, float* __restrict orgY, float* __restrict orgZ,
                            float* __restrict dirX, float* __restrict dirY, float* __restrict dirZ,
                            float* __restrict tnear, float* __restrict tfar, float* __restrict time,
                            unsigned* __restrict mask, unsigned* __restrict id,
                            unsigned* __restrict flags, const float* __restrict ox,
                            const float* __restrict oy, const float* __restrict oz,
                            const float* __restrict dx, const float* __restrict dy,
                            const float* __restrict dz) {
  const float inf = std::numeric_limits<float>::infinity();
  APERTURE_LANE_LOOP
  for (int k = 0; k < kLanes; ++k) {
    orgX[k] = ox[k];
    orgY[k] = oy[k];
    orgZ[k] = oz[k];
    dirX[k] = dx[k];
    dirY[k] = dy[k];
    dirZ[k] = dz[k];
    tnear[k] = 0.0f;
    tfar[k] = inf;
    time[k] = 0.0f;
    mask[k] = 0xFFFFFFFFu;
    id[k] = unsigned(k);
    flags[k] = 0;
  }
}

/// Writes the kLanes lanes of a block of rays with per-lane origins (storeBlockLanes into
/// `out`): the parallel projections, and the kernels of the other models with the origin
/// copied to every lane (vector stores either way).
template <int kLanes>
inline void writeBlockLanesWithOrigins(RayLanes& out, const float* ox, const float* oy,
                                       const float* oz, const float* dx, const float* dy,
                                       const float* dz) {
  storeBlockLanes<kLanes>(out.orgX, out.orgY, out.orgZ, out.dirX, out.dirY, out.dirZ, out.tnear,
                          out.tfar, out.time, out.mask, out.id, out.flags, ox, oy, oz, dx, dy, dz);
}

/// writeBlockLanesWithOrigins for rays from one origin (double, rounded once): the kernels of
/// the perspective, thin-lens, panorama and calibrated cameras.
template <int kLanes>
inline void writeBlockLanesFromOrigin(RayLanes& out, const glm::dvec3& org, const float* dx,
                                      const float* dy, const float* dz) {
  alignas(64) float ox[kLanes], oy[kLanes], oz[kLanes];
  APERTURE_LANE_LOOP
  for (int k = 0; k < kLanes; ++k) {
    ox[k] = float(org.x);
    oy[k] = float(org.y);
    oz[k] = float(org.z);
  }
  writeBlockLanesWithOrigins<kLanes>(out, ox, oy, oz, dx, dy, dz);
}

/// The per-lane copies of a block's per-column values (`columns`, kBW of them) and per-row
/// values (`rows`, kBH), in lanePixel's order: lane k gets columns[k mod kBW] and
/// rows[k / kBW]. This loop is unrolled (constant indices: broadcasts and shuffles), so the
/// kernel's lane loop that follows reads both with contiguous vector loads; indexing the
/// short arrays there by lane compiled to gathers (about twice the calibrated pinhole's time).
template <int kBW, int kBH, class T>
inline void spreadOverLanes(const T* columns, const T* rows, T* laneColumn, T* laneRow) {
  for (int k = 0; k < kBW * kBH; ++k) {
    const LanePixel offset = lanePixel(0, 0, kBW, k);
    laneColumn[k] = columns[offset.column];
    laneRow[k] = rows[offset.row];
  }
}

/// valid[k] of a kBW x kBH block at (column x0, row y0) whose every pixel has a ray: −1
/// inside the width x height image, 0 past its right or bottom edge (laneInImage).
template <int kBW, int kBH>
inline void writeBlockInImage(int x0, int y0, int width, int height, int* __restrict valid) {
  APERTURE_LANE_LOOP
  for (int k = 0; k < kBW * kBH; ++k)
    valid[k] = laneInImage(x0, y0, kBW, k, width, height) ? -1 : 0;
}

/// Calls f(bw, bh) with the frame loop's block shape (4x4, 4x2, 2x2 or 1x1) as
/// std::integral_constant arguments, so a kernel gets constant trip counts
/// (kernel<decltype(bw)::value, decltype(bh)::value>). False, without calling f, for any other
/// shape.
template <class F>
inline bool withBlockShape(int blockW, int blockH, F&& f) {
  using Four = std::integral_constant<int, 4>;
  using Two = std::integral_constant<int, 2>;
  using One = std::integral_constant<int, 1>;
  if (blockW == 4 && blockH == 4) return f(Four{}, Four{}), true;
  if (blockW == 4 && blockH == 2) return f(Four{}, Two{}), true;
  if (blockW == 2 && blockH == 2) return f(Two{}, Two{}), true;
  if (blockW == 1 && blockH == 1) return f(One{}, One{}), true;
  return false;
}

}  // namespace aperture
