#pragma once
// The benchmark ceiling: the camera's rays, generated once up front, traced by bare
// rtcIntersect16 with nothing else (no shading, no framebuffer).
#include <embree3/rtcore.h>

#include <cstdint>
#include <vector>

#include "core/camera.h"
#include "core/scene.h"

namespace aperture {

class BaselineTracer {
 public:
  /// Generates the 4x4-pixel packets of every pixel's centre ray (the rays of the geometry
  /// AOVs; at spp 1 the only sample), in the frame loop's tile order (tiles of `tileSize`),
  /// and keeps them (768 bytes a packet).
  BaselineTracer(const Camera& camera, int width, int height, int tileSize);
  /// Traces every packet with rtcIntersect16 (coherent flag) over TBB tiles; returns seconds.
  double traceFrame(const Scene& scene) const;
  uint64_t rayCount() const { return rays_; }

 private:
  struct Tile {
    size_t first, count;  // packets
  };
  std::vector<RTCRay16> rays16_;
  struct alignas(64) ValidMask {  // rtcIntersect16 requires a 64-byte aligned mask
    int lanes[16];
  };
  std::vector<ValidMask> valid_;
  std::vector<Tile> tiles_;
  uint64_t rays_ = 0;
};

}  // namespace aperture
