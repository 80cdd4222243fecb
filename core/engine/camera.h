#pragma once
// The camera interface the frame loop traces through. Models live in cameras/.
//
// Contract for generate():
//  - lane k of the packet is pixel lanePixel(x0, y0, blockW, k) (row y0 + k / blockW, column
//    x0 + k % blockW); lanes past the image's right or bottom edge (laneInImage false) are
//    invalid. These two functions are the only statement of the mapping: cameras, the frame
//    loop, the baseline tracer and the tests all call them;
//  - sample s in [0, spp) is a stratified sample of the pixel; PacketRequest::kCentreRay is
//    the ray through the pixel centre (j + ½, i + ½) and the lens centre, at any spp (at
//    spp 1 it equals sample 0). The geometry AOVs come from it;
//  - origins are in *render space*: world minus the scene's render origin (the mesh anchor),
//    computed in double and rounded to float once;
//  - directions are unit length (normalised in double, then rounded), so t is a distance;
//  - tnear = 0, tfar = +inf, time = 0, mask = 0xFFFFFFFF, flags = 0, id = lane. The one
//    exception: a perspective or thin-lens camera with a clip (near, far planar depths) sets
//    tnear = near / cos and tfar = far / cos, cos the direction's cosine with the view axis,
//    so exactly the depths in [near, far] are hit. The frame loop traces tnear and tfar as
//    given and never resets them;
//  - valid[k] = -1 for a lane to trace, 0 for a lane outside the image or without a ray
//    (a fisheye pixel outside its circle). Invalid lanes still get finite values.
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace aperture {

/// SoA pointers into one Embree RTCRayHitN (N = width); see rayLanes() in core/engine/packet.h.
struct RayLanes {
  int width = 0;
  float *orgX, *orgY, *orgZ, *tnear;
  float *dirX, *dirY, *dirZ, *time;
  float* tfar;
  unsigned *mask, *id, *flags;
};

/// Row i and column j of a lane's pixel.
struct LanePixel {
  int row, column;
  /// Whether the pixel lies inside a width x height image. Blocks start inside the image, so
  /// only the right and bottom edges can cut them: only the upper bounds are tested.
  constexpr bool inImage(int width, int height) const { return row < height && column < width; }
};

/// The pixel of lane k in a block of blockW columns whose top-left pixel is (row y0, column
/// x0): lanes run along the block's rows, row by row. Inline and branch-free, so a loop over
/// the lanes with a constant blockW stays vectorisable.
constexpr LanePixel lanePixel(int x0, int y0, int blockW, int k) {
  return {y0 + k / blockW, x0 + k % blockW};
}

/// Whether lane k (as lanePixel) lies inside a width x height image.
constexpr bool laneInImage(int x0, int y0, int blockW, int k, int width, int height) {
  return lanePixel(x0, y0, blockW, k).inImage(width, height);
}

/// The pixels and sample one packet covers.
struct PacketRequest {
  /// `sample` value asking for the centre ray: pixel centre (j + ½, i + ½), lens centre.
  static constexpr int kCentreRay = -1;

  int x0 = 0, y0 = 0;          ///< column and row of the block's top-left pixel
  int blockW = 4, blockH = 4;  ///< lanes = blockW * blockH, at most 16
  int sample = 0;              ///< sample index in [0, spp), or kCentreRay

  /// Lanes of the packet.
  int lanes() const { return blockW * blockH; }
  /// The pixel of lane k (lanePixel).
  LanePixel pixel(int k) const { return lanePixel(x0, y0, blockW, k); }
  /// Whether lane k lies inside a width x height image (laneInImage).
  bool inImage(int k, int width, int height) const {
    return laneInImage(x0, y0, blockW, k, width, height);
  }
  /// Whether the request asks for the centre ray rather than a stratified sample.
  bool centreRay() const { return sample == kCentreRay; }
};

/// The projection of an equirectangular panorama (no 4x4 matrix expresses it). With raster
/// (x, y) (pixel (i, j) centre at (j + ½, i + ½)) on a W x H image:
///   lon = lon0 + (x / W)·(lon1 − lon0),  lat = lat1 − (y / H)·(lat1 − lat0)
///   direction in standard camera space (see CameraDescription) = (cos lat·sin lon, sin lat,
///   cos lat·cos lon): (lon, lat) = (0, 0) looks along +z, lon = 90° along +x (right).
struct EquirectProjection {
  glm::dvec2 longitudeDeg{-180, 180};  ///< (lon0, lon1): longitude of the left and right edges
  glm::dvec2 latitudeDeg{-90, 90};     ///< (lat0, lat1): latitude of the bottom and top edges
};

/// The projection of an equidistant fisheye. With raster (x, y), centre (cx, cy) and radius R
/// in pixels and full field of view F:
///   a = (x − cx) / R,  b = (cy − y) / R,  ρ = √(a² + b²)  (ρ > 1: no ray)
///   θ = ρ·F / 2 (the angle from +z),  direction = (sin θ·a/ρ, sin θ·b/ρ, cos θ)
/// in standard camera space (see CameraDescription).
struct FisheyeProjection {
  double fovDeg = 180;       ///< F, degrees, across the circle's diameter
  glm::dvec2 centerPx{0.0};  ///< (cx, cy), raster (column, row)
  double radiusPx = 1;       ///< R, pixels
};

/// The lens of a calibrated camera (cameras/models/calibrated.h): no 4x4 matrix expresses a
/// distorted projection, so the model and its parameters are carried as they are.
struct LensProjection {
  std::string model;                    ///< COLMAP's model name: "OPENCV"
  std::vector<std::string> paramNames;  ///< COLMAP's order: fx, fy, cx, cy, k1, ...
  std::vector<double> params;           ///< pixels for focal lengths and principal point
  std::string pixelCentre;  ///< where params put pixel (i, j)'s centre: "half-integer", "integer"
};

/// Everything a file header or --describe needs to reproduce and re-project an image. The
/// matrices follow OpenEXR's standard attributes (which take Pixar RenderMan's spaces); GLM
/// column-vector convention here (p' = M p), written to the EXR transposed (Imath row vectors).
struct CameraDescription {
  std::string type;     ///< registry name: "perspective", "orthographic", ...
  glm::dvec3 eye{0.0};  ///< e, world space, scene units
  glm::dvec3 u{1, 0, 0}, v{0, 1, 0}, w{0, 0, 1};  ///< frame: right, up, backwards
  double d = 1;                                   ///< image-plane distance, scene units
  double vw = 1, vh = 1;                          ///< viewport size on the image plane, scene units
  int width = 0, height = 0;                      ///< image size, pixels
  int spp = 1;                                    ///< samples per pixel
  /// What OpenEXR's worldToCamera attribute holds. Its space is named exrCamera (the others
  /// are cvCamera and glCamera, cameras/lenses/calibration.h): left-handed with its origin at
  /// e, +x right (U), +y up (V), +z the viewing direction (−W), so points in front have z > 0
  /// and z is the planar depth Z. Built by exrCameraFromFrame() only.
  glm::dmat4 exrCameraFromWorld{1.0};
  /// OpenEXR's worldToNDC: after the homogeneous divide, (0, 0) is the top-left and (1, 1) the
  /// bottom-right corner of the display window (outer pixel edges), x right, y down: x =
  /// column / W, y = row / H, pixel (i, j) centre at ((j + ½) / W, (i + ½) / H). Empty for the
  /// panoramas, whose projection no 4x4 matrix expresses (see equirect, fisheye).
  std::optional<glm::dmat4> ndcFromWorld;
  /// OpenEXR's pixelAspectRatio: width over height of a pixel on the image plane (planar
  /// cameras: (vw / W) / (vh / H); equirect: degrees of longitude over degrees of latitude per
  /// pixel; fisheye: 1).
  double pixelAspectRatio = 1;
  /// OpenEXR's screen window: the image's rectangle on the plane z = 1 of camera space (centre,
  /// width), for perspective projections. OpenEXR's defaults (0, 0) and 1 for the others, as
  /// its definition prescribes for images without a perspective projection.
  glm::dvec2 screenWindowCenter{0.0};
  double screenWindowWidth = 1;
  std::optional<EquirectProjection> equirect;  ///< set for the equirect camera only
  std::optional<FisheyeProjection> fisheye;    ///< set for the fisheye camera only
  std::optional<LensProjection> lens;          ///< set for the calibrated camera only
  /// Extra parameters as (name, value) text pairs: fov, shift, aperture, focus, ...
  std::vector<std::pair<std::string, std::string>> extra;
};

/// The extra of a distorted lens's pixels with a ray, "N of W·H" (its direction table's count).
inline constexpr std::string_view kValidPixelsExtra = "valid_pixels";

/// Whether an extra of CameraDescription is counted over the image rather than stated by the
/// camera's parameters: it follows from those parameters (a lens compared exactly, the image
/// size), so comparisons of cameras leave it out, and describeWithoutCounts() does not count it.
inline bool isCountedExtra(std::string_view name) { return name == kValidPixelsExtra; }

/// The one definition of OpenEXR's camera space (see CameraDescription::exrCameraFromWorld) from
/// the frame e, U (right), V (up), W (backwards): rows U, V, −W and translation (−U·e, −V·e,
/// W·e). Column-vector GLM convention.
inline glm::dmat4 exrCameraFromFrame(const glm::dvec3& eye, const glm::dvec3& u,
                                     const glm::dvec3& v, const glm::dvec3& w) {
  const glm::dvec3 forward = -w;
  glm::dmat4 m(1.0);  // GLM: m[column][row]
  for (int c = 0; c < 3; ++c) {
    m[c][0] = u[c];
    m[c][1] = v[c];
    m[c][2] = forward[c];
  }
  m[3][0] = -glm::dot(u, eye);
  m[3][1] = -glm::dot(v, eye);
  m[3][2] = -glm::dot(forward, eye);
  return m;
}

/// Where the pixel-centre rays of each 4x4 block of an image cross the plane z = 1 of a camera
/// frame (a camera-space direction d crosses it at (d.x / d.z, d.y / d.z)), for a camera whose
/// rays all start at one point along directions no 4x4 matrix maps (a distorted lens): the
/// coverage mask bounds what each block sees through them (core/engine/coverage_mask.h).
struct LensBlockBounds {
  /// Render space to the camera frame (an orthonormal rotation about the eye; z forwards).
  glm::dmat4 cameraFromRender{1.0};
  glm::dvec3 eye{0.0};  ///< the exact eye, render space
  int width = 0, height = 0;
  /// Per block of 4 x 4 pixels from the top-left, row by row: (x0, y0, x1, y1) on the plane,
  /// holding every crossing; x0 > x1 for a block without a ray. Owned by the camera.
  const glm::vec4* blocks = nullptr;
  /// Per block, the pixels with a ray: bit 4·r + c for the block's row r and column c (none
  /// past the image's edges; each such ray is finite). Owned by the camera.
  const uint16_t* blockRays = nullptr;
  glm::dvec4 extent{0.0};  ///< the same over every ray
  double minCosine = 0;    ///< the least cosine of a ray with the frame's z axis
};

/// A camera's eye and W (pointing backwards, away from the view) in world space, in double.
struct WorldView {
  glm::dvec3 eye{0.0};
  glm::dvec3 w{0.0, 0.0, 1.0};
};

class Camera {
 public:
  virtual ~Camera() = default;
  /// Fills `out` (width = req.blockW * req.blockH lanes) and valid[0..width).
  virtual void generate(const PacketRequest& req, RayLanes& out, int* valid) const = 0;
  /// Unit view axis (−W) and eye in render space, for planar depth Z = dot(P − eye, axis).
  virtual glm::vec3 renderEye() const = 0;
  virtual glm::vec3 viewAxis() const = 0;
  virtual CameraDescription describe() const = 0;
  /// describe() without the extras it counts over the image (isCountedExtra): what the
  /// camera's parameters state, at no cost beyond them (a distorted lens builds no direction
  /// table for it). What --resume compares with a file's header.
  virtual CameraDescription describeWithoutCounts() const { return describe(); }
  /// describe()'s eye and w without the rest of the description, some of which costs work
  /// (a distorted lens counts the pixels its direction table gives a ray).
  virtual WorldView worldView() const {
    const CameraDescription c = describe();
    return {c.eye, c.w};
  }
  /// True when generate() uses random numbers (spp > 1 or a lens); the frame loop skips
  /// sample bookkeeping otherwise.
  virtual bool stochastic() const = 0;
  /// Raster position (x, y) of a world point through the model's full forward map (pixel
  /// (i, j) centre at (j + ½, i + ½)), or nothing where the point has no image: behind a
  /// pinhole or a parallel camera's image plane, outside a fisheye's field, outside the region
  /// where a lens's inverse returns the point's direction. The position may lie outside
  /// [0, W] x [0, H]. Thin lens: the centre of the circle of confusion.
  virtual std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const = 0;
  /// The centre ray (lens centre, as PacketRequest::kCentreRay) through raster position
  /// (x, y), continuous: origin in render space and unit direction, in double, before any
  /// rounding. False where the position has no ray (outputs still finite).
  virtual bool centreRayAt(double x, double y, glm::dvec3& renderOrg, glm::dvec3& dir) const = 0;
  /// The render-space point that every ray generate() gives starts from, each with tnear 0
  /// (one centre of projection and no clip), or nothing (a lens, a parallel projection, clip
  /// planes). Where it lies in the scene's box, no ray can miss the box, and the frame loop
  /// skips its scene-box test (core/engine/scene_box.h). Nothing is always a safe answer.
  virtual std::optional<glm::vec3> sharedRayOrigin() const { return std::nullopt; }
  /// For a camera with a shared ray origin and no projective map (describe().ndcFromWorld
  /// empty), whose every ray is a pixel-centre ray: where they cross a plane, block by block
  /// (LensBlockBounds), or nothing. Nothing is always a safe answer.
  virtual std::optional<LensBlockBounds> lensBlockBounds() const { return std::nullopt; }
};

}  // namespace aperture
