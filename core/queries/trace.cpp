#include "core/queries/trace.h"

#include <cmath>

#include "core/engine/intersect_scene.h"
#include "core/engine/packet.h"
#include "core/util/error.h"

namespace aperture {

namespace {

bool finiteRay(const TraceRay& r) {
  return std::isfinite(r.org.x) && std::isfinite(r.org.y) && std::isfinite(r.org.z) &&
         std::isfinite(r.dir.x) && std::isfinite(r.dir.y) && std::isfinite(r.dir.z) &&
         !std::isnan(r.tnear) && !std::isnan(r.tfar);
}

template <int N>
void traceAll(const Scene& scene, const std::vector<TraceRay>& rays, std::vector<TraceHit>& out) {
  alignas(64) typename PacketOf<N>::type packet;
  alignas(64) int valid[N];
  RayLanes lanes = rayLanes<N>(packet);
  const HitLanes h = hitLanes<N>(packet);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  for (size_t first = 0; first < rays.size(); first += N) {
    int active = 0;
    for (int k = 0; k < N; ++k) {
      const size_t i = first + size_t(k);
      const bool live = i < rays.size() && finiteRay(rays[i]);
      const TraceRay r = live ? rays[i] : TraceRay{};
      lanes.orgX[k] = r.org.x, lanes.orgY[k] = r.org.y, lanes.orgZ[k] = r.org.z;
      lanes.dirX[k] = r.dir.x, lanes.dirY[k] = r.dir.y, lanes.dirZ[k] = r.dir.z;
      lanes.tnear[k] = r.tnear, lanes.tfar[k] = r.tfar, lanes.time[k] = 0.0f;
      lanes.mask[k] = 0xFFFFFFFFu, lanes.id[k] = unsigned(k), lanes.flags[k] = 0;
      valid[k] = live ? -1 : 0;
      active += live;
    }
    if (active == 0) continue;
    clearHits<N>(packet);
    intersectScene<N>(scene, &ctx, valid, packet);
    for (int k = 0; k < N && first + size_t(k) < rays.size(); ++k) {
      if (!valid[k] || h.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
      TraceHit& hit = out[first + size_t(k)];
      hit.t = h.tfar[k];
      hit.ng = glm::vec3(h.ngX[k], h.ngY[k], h.ngZ[k]);
      if constexpr (N == 1) {
        hit.u = packet.hit.u, hit.v = packet.hit.v;
      } else {
        hit.u = packet.hit.u[k], hit.v = packet.hit.v[k];
      }
      hit.geomId = h.instID[k] == RTC_INVALID_GEOMETRY_ID ? h.geomID[k] : h.instID[k];
      hit.primId = scene.sourcePrimId(hit.geomId, h.primID[k]);
    }
  }
}

}  // namespace

std::vector<TraceHit> traceRays(const Scene& scene, const std::vector<TraceRay>& rays,
                                int packetWidth) {
  std::vector<TraceHit> out(rays.size());
  switch (packetWidth) {
    case 1:
      traceAll<1>(scene, rays, out);
      break;
    case 4:
      traceAll<4>(scene, rays, out);
      break;
    case 8:
      traceAll<8>(scene, rays, out);
      break;
    case 16:
      traceAll<16>(scene, rays, out);
      break;
    default:
      throw Error(cat("traceRays: packet width ", packetWidth, " is not 1, 4, 8 or 16"));
  }
  return out;
}

}  // namespace aperture
