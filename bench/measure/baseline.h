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

#include "core/engine/camera.h"
#include "core/engine/scene.h"
#include "core/util/error.h"

namespace aperture {

/// The Embree call the baseline traces with.
enum class BaselineApi {
  Packet16,  ///< rtcIntersect16 per 4x4 block (the frame loop's call)
  StreamNM,  ///< rtcIntersectNM: the tile's 4x4 packets as one stream of RTCRayHit16
  Stream1M,  ///< rtcIntersect1M: the tile's rays as one stream of single RTCRayHit
};

/// Parses "packet16", "stream-nm" or "stream-1m" (Error naming `flag` otherwise).
BaselineApi parseBaselineApi(const std::string& text, const char* flag);
const char* baselineApiName(BaselineApi api);

class BaselineTracer {
 public:
  /// Plans the 4x4-pixel packets of every pixel's centre ray (the rays of the geometry AOVs;
  /// at spp 1 the only sample) in the frame loop's tile order (tiles of `tileSize`).
  /// Every API traces the same rays with the coherent flag; the streams are the trial of
  /// issue 13 (does Embree's stream API move the ceiling?).
  BaselineTracer(const Camera& camera, int width, int height, int tileSize,
                 BaselineApi api = BaselineApi::Packet16);
  /// Traces every packet with rtcIntersect16 (coherent flag) over TBB tiles; returns seconds.
  double traceFrame(const Scene& scene) const;
  /// Traces the frame as traceFrame and counts the rays that hit (tests: every API must hit
  /// what the frame loop hits).
  uint64_t countHits(const Scene& scene) const;
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
  void traceTilePinhole(const Scene& scene, const Tile& t, RTCIntersectContext& ctx,
                        uint64_t* hits) const;
  void traceTileStored(const Scene& scene, const Tile& t, RTCIntersectContext& ctx,
                       uint64_t* hits) const;
  /// The tile's packets (made by the pinhole or copied) as one stream call.
  void traceTileStream(const Scene& scene, const Tile& t, RTCIntersectContext& ctx,
                       uint64_t* hits) const;
  /// Traces every tile in parallel; adds the hit count to `hits` when given.
  void traceTiles(const Scene& scene, uint64_t* hits) const;
  /// The rays of the 4x4 block at (x0, y0): packet p of the pre-generated rays, or the pinhole.
  void blockRays(int x0, int y0, size_t p, RTCRay16& rays, int* valid) const;

  int width_, height_;
  BaselineApi api_;
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
