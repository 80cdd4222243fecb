#pragma once
// The camera interface the frame loop traces through. Models live in cameras/.
//
// Contract for generate():
//  - lane k of the packet is pixel (row y0 + k / blockW, column x0 + k % blockW);
//  - origins are in *render space*: world minus the scene's render origin (the mesh anchor),
//    computed in double and rounded to float once;
//  - directions are unit length (normalised in double, then rounded), so t is a distance;
//  - tnear = 0, tfar = +inf, time = 0, mask = 0xFFFFFFFF, flags = 0, id = lane;
//  - valid[k] = -1 for a lane to trace, 0 for a lane outside the image or without a ray
//    (a fisheye pixel outside its circle). Invalid lanes still get finite values.
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <vector>

namespace aperture {

/// SoA pointers into one Embree RTCRayHitN (N = width); see rayLanes() in core/packet.h.
struct RayLanes {
  int width = 0;
  float *orgX, *orgY, *orgZ, *tnear;
  float *dirX, *dirY, *dirZ, *time;
  float* tfar;
  unsigned *mask, *id, *flags;
};

/// The pixels and sample one packet covers.
struct PacketRequest {
  int x0 = 0, y0 = 0;          ///< column and row of the block's top-left pixel
  int blockW = 4, blockH = 4;  ///< lanes = blockW * blockH, at most 16
  int sample = 0;              ///< sample index in [0, spp)
};

/// Everything a file header or --describe needs to reproduce and re-project an image.
struct CameraDescription {
  std::string type;     ///< registry name: "perspective", "orthographic", ...
  glm::dvec3 eye{0.0};  ///< e, world space, scene units
  glm::dvec3 u{1, 0, 0}, v{0, 1, 0}, w{0, 0, 1};  ///< frame: right, up, backwards
  double d = 1;                                   ///< image-plane distance, scene units
  double vw = 1, vh = 1;                          ///< viewport size on the image plane, scene units
  int width = 0, height = 0;                      ///< image size, pixels
  int spp = 1;                                    ///< samples per pixel
  /// Camera space: origin at e, axes (U, V, W). Column-vector convention (p' = M p).
  glm::dmat4 cameraFromWorld{1.0};
  /// NDC: x = column / width, y = row / height (continuous; pixel (i, j) centre at
  /// ((j + 0.5) / W, (i + 0.5) / H)), after the homogeneous divide. Identity where the
  /// projection is not linear (panoramas).
  glm::dmat4 ndcFromWorld{1.0};
  /// Extra parameters as (name, value) text pairs: fov, shift, aperture, focus, ...
  std::vector<std::pair<std::string, std::string>> extra;
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
  /// True when generate() uses random numbers (spp > 1 or a lens); the frame loop skips
  /// sample bookkeeping otherwise.
  virtual bool stochastic() const = 0;
};

}  // namespace aperture
