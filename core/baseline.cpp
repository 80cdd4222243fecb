#include "core/baseline.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <chrono>
#include <cstring>

#include "core/packet.h"
#include "core/parallel.h"

namespace aperture {

BaselineTracer::BaselineTracer(const Camera& camera, int width, int height, int tileSize) {
  const int tilesX = (width + tileSize - 1) / tileSize;
  const int tilesY = (height + tileSize - 1) / tileSize;
  alignas(64) RTCRayHit16 packet;
  RayLanes lanes = rayLanes<16>(packet);
  for (int tile = 0; tile < tilesX * tilesY; ++tile) {
    const int x0 = (tile % tilesX) * tileSize, y0 = (tile / tilesX) * tileSize;
    const int x1 = std::min(x0 + tileSize, width), y1 = std::min(y0 + tileSize, height);
    Tile t{rays16_.size(), 0};
    for (int by = y0; by < y1; by += 4)
      for (int bx = x0; bx < x1; bx += 4) {
        ValidMask valid;
        const PacketRequest req{bx, by, 4, 4, PacketRequest::kCentreRay};
        camera.generate(req, lanes, valid.lanes);
        for (int k = 0; k < 16; ++k) {
          if (!req.inImage(k, width, height)) valid.lanes[k] = 0;
          rays_ += valid.lanes[k] != 0;
        }
        rays16_.push_back(packet.ray);
        valid_.push_back(valid);
        ++t.count;
      }
    tiles_.push_back(t);
  }
}

double BaselineTracer::traceFrame(const Scene& scene) const {
  const auto start = std::chrono::steady_clock::now();
  parallelFor(tiles_.size(), 1, [&](size_t first, size_t last) {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) RTCRayHit16 packet;
    for (size_t t = first; t != last; ++t)
      for (size_t p = tiles_[t].first; p < tiles_[t].first + tiles_[t].count; ++p) {
        packet.ray = rays16_[p];
        clearHits<16>(packet);
        rtcIntersect16(valid_[p].lanes, scene.handle(), &ctx, &packet);
      }
  });
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace aperture
