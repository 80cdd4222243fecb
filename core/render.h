#pragma once
// The tiled, multithreaded frame loop: camera packets -> rtcIntersectN -> AOV framebuffers.
#include <cstdint>

#include "core/camera.h"
#include "core/framebuffer.h"
#include "core/scene.h"

namespace aperture {

struct RenderSettings {
  int packetWidth = 16;  ///< 1, 4, 8 or 16 rays per rtcIntersectN call (blocks 1x1, 2x2, 4x2, 4x4)
  int tileSize = 32;     ///< tile edge in pixels (a multiple of 4); tiles are the unit of TBB work
  int spp = 1;           ///< samples per pixel (must match the camera's)
};

struct RenderStats {
  double seconds = 0;        ///< wall time of the frame
  uint64_t raysTraced = 0;   ///< rays passed to Embree with a valid lane
  uint64_t raysSkipped = 0;  ///< lanes masked because the camera gave no ray or it was non-finite
  uint64_t hits = 0;
  double mraysPerSecond() const { return seconds > 0 ? raysTraced / seconds * 1e-6 : 0; }
};

/// Renders one frame into `fb` (its size and AOV set decide what is computed). Threads come
/// from the ambient TBB arena (limit them with tbb::global_control). The result is
/// bit-identical for any thread count, tile size and packet width. FTZ/DAZ are set on every
/// worker. Throws Error for bad settings.
RenderStats renderImage(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                        Framebuffer& fb);

/// Checks settings (packet width in {1,4,8,16}, tile size a positive multiple of 4 up to
/// 4096); throws Error naming the bad value. spp is the camera's, checked by the camera
/// schema; renderImage requires settings.spp to equal it.
void validateRenderSettings(const RenderSettings& settings);

}  // namespace aperture
