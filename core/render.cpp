#include "core/render.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include "core/error.h"
#include "core/packet.h"
#include "core/parallel.h"

namespace aperture {

void validateRenderSettings(const RenderSettings& s) {
  if (s.packetWidth != 1 && s.packetWidth != 4 && s.packetWidth != 8 && s.packetWidth != 16)
    throw Error(cat("packet width ", s.packetWidth, " is not one of 1, 4, 8, 16"));
  if (s.tileSize < 4 || s.tileSize > 4096 || s.tileSize % 4 != 0)
    throw Error(cat("tile size ", s.tileSize, " must be a multiple of 4 in [4, 4096]"));
  if (s.spp < 1 || s.spp > 65536) throw Error(cat("spp ", s.spp, " must be in [1, 65536]"));
}

namespace {

/// What one frame computes, decided once from the framebuffer's AOVs.
struct ImagePlan {
  const Scene& scene;
  const Camera& camera;
  Framebuffer& fb;
  RenderSettings settings;
  glm::vec3 eye, axis;  // render space
  glm::dvec3 origin;    // world position of the render-space origin
  bool color, depth, distance, normal, position, primId, geomId;
  bool anyGeometry;   // any AOV filled from sample 0 only
  bool instanced;     // normals of instanced hits need the instance's normal matrix
  bool remapPrimIds;  // the scene was culled: primID goes through Scene::originalPrimId
};

struct TileCounters {
  uint64_t traced = 0, skipped = 0, hits = 0;
};

inline bool finiteLane(const RayLanes& l, int k) {
  return std::isfinite(l.orgX[k]) && std::isfinite(l.orgY[k]) && std::isfinite(l.orgZ[k]) &&
         std::isfinite(l.dirX[k]) && std::isfinite(l.dirY[k]) && std::isfinite(l.dirZ[k]);
}

template <int N>
void renderTile(const ImagePlan& plan, int x0, int y0, int x1, int y1, TileCounters& count) {
  constexpr int kBW = blockWidthFor(N), kBH = blockHeightFor(N);
  // Denormals flushed on every worker (Embree's recommendation); same mode on all threads.
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);

  alignas(64) typename PacketOf<N>::type packet;
  alignas(64) int valid[N];
  RayLanes lanes = rayLanes<N>(packet);
  const HitLanes h = hitLanes<N>(packet);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;

  Framebuffer& fb = plan.fb;
  // Only color averages samples; the geometry AOVs come from sample 0, so without color the
  // other samples are neither generated nor traced.
  const int spp = plan.color ? plan.settings.spp : 1;
  const bool needNormal = plan.color || plan.normal;
  for (int by = y0; by < y1; by += kBH) {
    for (int bx = x0; bx < x1; bx += kBW) {
      float shade[N] = {}, cover[N] = {};
      for (int s = 0; s < spp; ++s) {
        plan.camera.generate(PacketRequest{bx, by, kBW, kBH, s}, lanes, valid);
        // Lanes outside the image, or whose ray is not finite, are never traced.
        int active = 0, nonFinite = 0;
        for (int k = 0; k < N; ++k) {
          const bool inside = by + k / kBW < fb.height && bx + k % kBW < fb.width;
          const bool live = valid[k] != 0 && inside;
          const bool finite = finiteLane(lanes, k);
          nonFinite += live && !finite;
          valid[k] = live && finite ? -1 : 0;
          active += live && finite;
        }
        count.skipped += uint64_t(nonFinite);
        if (active == 0) continue;
        clearHits<N>(packet);
        intersect<N>(plan.scene.handle(), &ctx, valid, packet);
        count.traced += uint64_t(active);

        // Per-lane values in SoA passes (vectorisable), then stores for hit lanes only.
        alignas(64) float nx[N] = {}, ny[N] = {}, nz[N] = {};
        alignas(64) int hitLane[N];
        int hitCount = 0;
        for (int k = 0; k < N; ++k) {
          hitLane[k] = valid[k] != 0 && h.geomID[k] != RTC_INVALID_GEOMETRY_ID;
          hitCount += hitLane[k];
        }
        if (hitCount == 0) continue;
        count.hits += uint64_t(hitCount);
        if (needNormal) {
          for (int k = 0; k < N; ++k) {
            nx[k] = h.ngX[k], ny[k] = h.ngY[k], nz[k] = h.ngZ[k];
          }
          if (plan.instanced)
            for (int k = 0; k < N; ++k)
              if (hitLane[k] && h.instID[k] != RTC_INVALID_GEOMETRY_ID) {
                const glm::vec3 n =
                    plan.scene.normalFromMesh(h.instID[k]) * glm::vec3(nx[k], ny[k], nz[k]);
                nx[k] = n.x, ny[k] = n.y, nz[k] = n.z;
              }
          for (int k = 0; k < N; ++k) {
            const float len2 = nx[k] * nx[k] + ny[k] * ny[k] + nz[k] * nz[k];
            const float inv = len2 > 0.0f ? 1.0f / std::sqrt(len2) : 0.0f;
            nx[k] *= inv, ny[k] *= inv, nz[k] *= inv;
          }
        }
        if (plan.color)
          for (int k = 0; k < N; ++k) {
            const float c =
                std::fabs(nx[k] * lanes.dirX[k] + ny[k] * lanes.dirY[k] + nz[k] * lanes.dirZ[k]);
            shade[k] += hitLane[k] ? c : 0.0f;
            cover[k] += hitLane[k] ? 1.0f : 0.0f;
          }
        if (s != 0 || !plan.anyGeometry) continue;
        alignas(64) float z[N];
        if (plan.depth)
          for (int k = 0; k < N; ++k)
            z[k] = (lanes.orgX[k] - plan.eye.x) * plan.axis.x +
                   (lanes.orgY[k] - plan.eye.y) * plan.axis.y +
                   (lanes.orgZ[k] - plan.eye.z) * plan.axis.z +
                   h.tfar[k] * (lanes.dirX[k] * plan.axis.x + lanes.dirY[k] * plan.axis.y +
                                lanes.dirZ[k] * plan.axis.z);
        for (int k = 0; k < N; ++k) {
          if (!hitLane[k]) continue;
          const size_t px = size_t(by + k / kBW) * size_t(fb.width) + size_t(bx + k % kBW);
          const float t = h.tfar[k];
          if (plan.depth) fb.depth[px] = z[k];
          if (plan.distance) fb.distance[px] = t;
          if (plan.normal) {
            fb.normal[3 * px] = nx[k];
            fb.normal[3 * px + 1] = ny[k];
            fb.normal[3 * px + 2] = nz[k];
          }
          if (plan.position) {
            // Hit point in double: render-space origin + org + t·dir, then rounded once.
            const glm::dvec3 p =
                plan.origin + glm::dvec3(lanes.orgX[k], lanes.orgY[k], lanes.orgZ[k]) +
                double(t) * glm::dvec3(lanes.dirX[k], lanes.dirY[k], lanes.dirZ[k]);
            fb.position[3 * px] = float(p.x);
            fb.position[3 * px + 1] = float(p.y);
            fb.position[3 * px + 2] = float(p.z);
          }
          if (plan.primId)
            fb.primId[px] =
                plan.remapPrimIds
                    ? plan.scene.originalPrimId(
                          h.instID[k] == RTC_INVALID_GEOMETRY_ID ? h.geomID[k] : h.instID[k],
                          h.primID[k])
                    : h.primID[k];
          if (plan.geomId)
            fb.geomId[px] = h.instID[k] == RTC_INVALID_GEOMETRY_ID ? h.geomID[k] : h.instID[k];
        }
      }
      if (!plan.color) continue;
      const float inv = 1.0f / float(spp);
      for (int k = 0; k < N; ++k) {
        const int i = by + k / kBW, j = bx + k % kBW;
        if (i >= fb.height || j >= fb.width) continue;
        float* rgba = &fb.rgba[4 * (size_t(i) * size_t(fb.width) + size_t(j))];
        const float c = shade[k] * inv;
        rgba[0] = rgba[1] = rgba[2] = c;
        rgba[3] = cover[k] * inv;
      }
    }
  }
}

}  // namespace

RenderStats renderImage(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                        Framebuffer& fb) {
  validateRenderSettings(settings);
  if (fb.width <= 0 || fb.height <= 0 || fb.aovs == 0)
    throw Error(cat("framebuffer ", fb.width, "x", fb.height, " with AOVs '",
                    aovListString(fb.aovs), "' is empty"));
  const CameraDescription desc = camera.describe();
  if (desc.width != fb.width || desc.height != fb.height || desc.spp != settings.spp)
    throw Error(cat("camera image ", desc.width, "x", desc.height, " spp ", desc.spp,
                    " does not match the framebuffer ", fb.width, "x", fb.height, " spp ",
                    settings.spp));
  ImagePlan plan{scene,
                 camera,
                 fb,
                 settings,
                 camera.renderEye(),
                 camera.viewAxis(),
                 scene.renderOrigin(),
                 fb.has(kAovColor),
                 fb.has(kAovDepth),
                 fb.has(kAovDistance),
                 fb.has(kAovNormal),
                 fb.has(kAovPosition),
                 fb.has(kAovPrimId),
                 fb.has(kAovGeomId),
                 false,
                 scene.instanceCount() > 0,
                 scene.remapsPrimIds()};
  plan.anyGeometry =
      plan.depth || plan.distance || plan.normal || plan.position || plan.primId || plan.geomId;

  const int ts = settings.tileSize;
  const int tilesX = (fb.width + ts - 1) / ts, tilesY = (fb.height + ts - 1) / ts;
  std::atomic<uint64_t> traced{0}, skipped{0}, hits{0};
  const auto start = std::chrono::steady_clock::now();
  parallelFor(size_t(tilesX) * size_t(tilesY), 1, [&](size_t first, size_t last) {
    for (int tile = int(first); tile != int(last); ++tile) {
      const int x0 = (tile % tilesX) * ts, y0 = (tile / tilesX) * ts;
      const int x1 = std::min(x0 + ts, fb.width), y1 = std::min(y0 + ts, fb.height);
      TileCounters c;
      switch (settings.packetWidth) {
        case 1:
          renderTile<1>(plan, x0, y0, x1, y1, c);
          break;
        case 4:
          renderTile<4>(plan, x0, y0, x1, y1, c);
          break;
        case 8:
          renderTile<8>(plan, x0, y0, x1, y1, c);
          break;
        default:
          renderTile<16>(plan, x0, y0, x1, y1, c);
          break;
      }
      traced += c.traced;
      skipped += c.skipped;
      hits += c.hits;
    }
  });
  RenderStats stats;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.raysTraced = traced;
  stats.raysSkipped = skipped;
  stats.hits = hits;
  return stats;
}

}  // namespace aperture
