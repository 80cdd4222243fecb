#pragma once
// The benchmark ceiling: bare rtcIntersect16 on the camera's rays with nothing else (no
// shading, no framebuffer). For a pinhole perspective camera (the bench's reference views)
// each packet's rays are made in the same loop by a minimal float ray generation, so the
// baseline pays what any renderer must pay to have rays and no more; other cameras' rays are
// generated once up front and copied in.
#include <embree3/rtcore.h>

#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/scene.h"

namespace aperture {

class BaselineTracer {
 public:
  /// Plans the 4x4-pixel packets of every pixel's centre ray (the rays of the geometry AOVs;
  /// at spp 1 the only sample) in the frame loop's tile order (tiles of `tileSize`).
  BaselineTracer(const Camera& camera, int width, int height, int tileSize);
  /// Traces every packet with rtcIntersect16 (coherent flag) over TBB tiles; returns seconds.
  double traceFrame(const Scene& scene) const;
  uint64_t rayCount() const { return rays_; }
  /// How the rays are made: "float pinhole in the loop" or "pre-generated".
  std::string rayGeneration() const;
  /// The rays the pinhole mode traces for the 4x4 block at (x0, y0), and its lane mask (tests
  /// compare them with the camera's own rays). Only when rayGeneration() is the pinhole.
  void pinholeRays(int x0, int y0, RTCRay16& rays, int* valid) const;

 private:
  struct Tile {
    int x0, y0, x1, y1;  // pixels
    size_t firstPacket;  // into rays16_ (pre-generated rays only)
  };
  /// The minimal pinhole: the unit direction of pixel (i, j) is normalize(corner + j·du + i·dv)
  /// in float (corner: pixel (0, 0)'s centre on the image plane relative to the eye).
  struct Pinhole {
    glm::vec3 eye, corner, du, dv;
  };
  void traceTilePinhole(const Scene& scene, const Tile& t, RTCIntersectContext& ctx) const;
  void traceTileStored(const Scene& scene, const Tile& t, RTCIntersectContext& ctx) const;

  int width_, height_;
  bool pinhole_ = false;
  Pinhole p_{};
  std::vector<RTCRay16> rays16_;  // pre-generated rays (not a pinhole)
  struct alignas(64) ValidMask {  // rtcIntersect16 requires a 64-byte aligned mask
    int lanes[16];
  };
  std::vector<ValidMask> valid_;
  std::vector<Tile> tiles_;
  uint64_t rays_ = 0;
};

}  // namespace aperture
