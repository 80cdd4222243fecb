#include "core/render.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/packet.h"

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
struct FramePlan {
  const Scene& scene;
  const Camera& camera;
  Framebuffer& fb;
  RenderSettings settings;
  glm::vec3 eye, axis;  // render space
  glm::dvec3 origin;    // world position of the render-space origin
  bool color, depth, distance, normal, position, primId, geomId;
  bool anyGeometry;     // any AOV filled from sample 0 only
};

struct TileCounters {
  uint64_t traced = 0, skipped = 0, hits = 0;
};

inline bool finiteLane(const RayLanes& l, int k) {
  return std::isfinite(l.orgX[k]) && std::isfinite(l.orgY[k]) && std::isfinite(l.orgZ[k]) &&
         std::isfinite(l.dirX[k]) && std::isfinite(l.dirY[k]) && std::isfinite(l.dirZ[k]);
}

template <int N>
void renderTile(const FramePlan& plan, int x0, int y0, int x1, int y1, TileCounters& count) {
  constexpr int kBW = blockWidthFor(N), kBH = blockHeightFor(N);
  // Denormals flushed on every worker (Embree's recommendation); same mode on all threads.
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);

  alignas(64) typename PacketOf<N>::type packet;
  alignas(64) int valid[N];
  RayLanes lanes = rayLanes<N>(packet);
  const HitView<N> hit{packet};
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;

  Framebuffer& fb = plan.fb;
  const int spp = plan.settings.spp;
  const bool needNormal = plan.color || plan.normal;
  for (int by = y0; by < y1; by += kBH) {
    for (int bx = x0; bx < x1; bx += kBW) {
      float shade[N] = {}, cover[N] = {};
      for (int s = 0; s < spp; ++s) {
        plan.camera.generate(PacketRequest{bx, by, kBW, kBH, s}, lanes, valid);
        int active = 0;
        for (int k = 0; k < N; ++k) {
          if (by + k / kBW >= fb.height || bx + k % kBW >= fb.width) valid[k] = 0;
          if (valid[k] && !finiteLane(lanes, k)) {
            valid[k] = 0;
            ++count.skipped;
          }
          active += valid[k] != 0;
        }
        if (active == 0) continue;
        clearHits<N>(packet);
        intersect<N>(plan.scene.handle(), &ctx, valid, packet);
        count.traced += uint64_t(active);

        for (int k = 0; k < N; ++k) {
          if (!valid[k] || hit.geomID(k) == RTC_INVALID_GEOMETRY_ID) continue;
          ++count.hits;
          const size_t px = size_t(by + k / kBW) * size_t(fb.width) + size_t(bx + k % kBW);
          const float t = hit.t(k);
          glm::vec3 n(0.0f);
          const unsigned inst = hit.instID(k);
          const unsigned object = inst == RTC_INVALID_GEOMETRY_ID ? hit.geomID(k) : inst;
          if (needNormal) {
            glm::vec3 ng(hit.ngX(k), hit.ngY(k), hit.ngZ(k));
            if (inst != RTC_INVALID_GEOMETRY_ID) ng = plan.scene.normalFromMesh(inst) * ng;
            n = glm::normalize(ng);
          }
          if (plan.color) {
            const glm::vec3 dir(lanes.dirX[k], lanes.dirY[k], lanes.dirZ[k]);
            shade[k] += std::fabs(glm::dot(n, dir));
            cover[k] += 1.0f;
          }
          if (s != 0 || !plan.anyGeometry) continue;
          if (plan.depth) {
            const glm::vec3 org(lanes.orgX[k], lanes.orgY[k], lanes.orgZ[k]);
            const glm::vec3 dir(lanes.dirX[k], lanes.dirY[k], lanes.dirZ[k]);
            fb.depth[px] = glm::dot(org - plan.eye, plan.axis) + t * glm::dot(dir, plan.axis);
          }
          if (plan.distance) fb.distance[px] = t;
          if (plan.normal) {
            fb.normal[3 * px] = n.x;
            fb.normal[3 * px + 1] = n.y;
            fb.normal[3 * px + 2] = n.z;
          }
          if (plan.position) {
            // Hit point in double: render-space origin + org + t·dir, then rounded once.
            const glm::dvec3 p = plan.origin +
                                 glm::dvec3(lanes.orgX[k], lanes.orgY[k], lanes.orgZ[k]) +
                                 double(t) * glm::dvec3(lanes.dirX[k], lanes.dirY[k], lanes.dirZ[k]);
            fb.position[3 * px] = float(p.x);
            fb.position[3 * px + 1] = float(p.y);
            fb.position[3 * px + 2] = float(p.z);
          }
          if (plan.primId) fb.primId[px] = hit.primID(k);
          if (plan.geomId) fb.geomId[px] = object;
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

RenderStats renderFrame(const Scene& scene, const Camera& camera, const RenderSettings& settings,
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
  FramePlan plan{scene, camera, fb, settings, camera.renderEye(), camera.viewAxis(),
                 scene.renderOrigin(), fb.has(kAovColor), fb.has(kAovDepth),
                 fb.has(kAovDistance), fb.has(kAovNormal), fb.has(kAovPosition),
                 fb.has(kAovPrimId), fb.has(kAovGeomId), false};
  plan.anyGeometry = plan.depth || plan.distance || plan.normal || plan.position ||
                     plan.primId || plan.geomId;

  const int ts = settings.tileSize;
  const int tilesX = (fb.width + ts - 1) / ts, tilesY = (fb.height + ts - 1) / ts;
  std::atomic<uint64_t> traced{0}, skipped{0}, hits{0};
  const auto start = std::chrono::steady_clock::now();
  tbb::parallel_for(
      tbb::blocked_range<int>(0, tilesX * tilesY, 1),
      [&](const tbb::blocked_range<int>& range) {
        for (int tile = range.begin(); tile != range.end(); ++tile) {
          const int x0 = (tile % tilesX) * ts, y0 = (tile / tilesX) * ts;
          const int x1 = std::min(x0 + ts, fb.width), y1 = std::min(y0 + ts, fb.height);
          TileCounters c;
          switch (settings.packetWidth) {
            case 1: renderTile<1>(plan, x0, y0, x1, y1, c); break;
            case 4: renderTile<4>(plan, x0, y0, x1, y1, c); break;
            case 8: renderTile<8>(plan, x0, y0, x1, y1, c); break;
            default: renderTile<16>(plan, x0, y0, x1, y1, c); break;
          }
          traced += c.traced;
          skipped += c.skipped;
          hits += c.hits;
        }
      },
      tbb::simple_partitioner());
  RenderStats stats;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.raysTraced = traced;
  stats.raysSkipped = skipped;
  stats.hits = hits;
  return stats;
}

}  // namespace aperture
