#pragma once
// Embree packet types by width, RayLanes views into them, and the gate every packet passes
// on its way into Embree (sealLanes).
#include <embree3/rtcore.h>

#include <atomic>
#include <cmath>

#include "core/engine/camera.h"
#include "core/util/vector_kernel.h"

namespace aperture {

template <int N>
struct PacketOf;
template <>
struct PacketOf<1> {
  using type = RTCRayHit;
};
template <>
struct PacketOf<4> {
  using type = RTCRayHit4;
};
template <>
struct PacketOf<8> {
  using type = RTCRayHit8;
};
template <>
struct PacketOf<16> {
  using type = RTCRayHit16;
};

/// Block shape (columns x rows) of a packet of N rays: 1x1, 2x2, 4x2, 4x4.
constexpr int blockWidthFor(int n) { return n == 1 ? 1 : n == 4 ? 2 : 4; }
constexpr int blockHeightFor(int n) { return n / blockWidthFor(n); }

/// Lane pointers into an RTCRayHitN (for N = 1 the scalar fields).
template <int N>
RayLanes rayLanes(typename PacketOf<N>::type& p) {
  RayLanes l;
  l.width = N;
  if constexpr (N == 1) {
    l.orgX = &p.ray.org_x, l.orgY = &p.ray.org_y, l.orgZ = &p.ray.org_z, l.tnear = &p.ray.tnear;
    l.dirX = &p.ray.dir_x, l.dirY = &p.ray.dir_y, l.dirZ = &p.ray.dir_z, l.time = &p.ray.time;
    l.tfar = &p.ray.tfar, l.mask = &p.ray.mask, l.id = &p.ray.id, l.flags = &p.ray.flags;
  } else {
    l.orgX = p.ray.org_x, l.orgY = p.ray.org_y, l.orgZ = p.ray.org_z, l.tnear = p.ray.tnear;
    l.dirX = p.ray.dir_x, l.dirY = p.ray.dir_y, l.dirZ = p.ray.dir_z, l.time = p.ray.time;
    l.tfar = p.ray.tfar, l.mask = p.ray.mask, l.id = p.ray.id, l.flags = p.ray.flags;
  }
  return l;
}

/// Per-lane hit fields of an RTCRayHitN after intersection, as SoA pointers. u, v: Embree's
/// barycentric hit coordinates, the hit point being (1 − u − v)·v0 + u·v1 + v·v2 for the
/// triangle's vertices in index-buffer order.
struct HitLanes {
  const float *tfar, *ngX, *ngY, *ngZ;
  const unsigned *geomID, *primID, *instID;
  const float *u, *v;
};

template <int N>
HitLanes hitLanes(const typename PacketOf<N>::type& p) {
  if constexpr (N == 1)
    return {&p.ray.tfar,   &p.hit.Ng_x,      &p.hit.Ng_y, &p.hit.Ng_z, &p.hit.geomID,
            &p.hit.primID, &p.hit.instID[0], &p.hit.u,    &p.hit.v};
  else
    return {p.ray.tfar,   p.hit.Ng_x,      p.hit.Ng_y, p.hit.Ng_z, p.hit.geomID,
            p.hit.primID, p.hit.instID[0], p.hit.u,    p.hit.v};
}

/// An aligned Embree packet of N rays with its lane mask and the SoA views into it: what the
/// frame loop's and the layer passes' per-thread packets share. Not copyable (the views point
/// into it).
template <int N>
struct PacketBuffers {
  alignas(64) typename PacketOf<N>::type packet;
  alignas(64) int valid[N];
  RayLanes lanes;
  HitLanes hits;

  PacketBuffers() : lanes(rayLanes<N>(packet)), hits(hitLanes<N>(packet)) {}
  PacketBuffers(const PacketBuffers&) = delete;
  PacketBuffers& operator=(const PacketBuffers&) = delete;
};

/// Sets hit.geomID of every lane to RTC_INVALID_GEOMETRY_ID (required before rtcIntersect).
template <int N>
void clearHits(typename PacketOf<N>::type& p) {
  if constexpr (N == 1) {
    p.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    p.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  } else {
    for (int k = 0; k < N; ++k) {
      p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      p.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
  }
}

/// The largest magnitude of a ray's origin and direction components that Embree takes: its
/// packet kernels assert |x| <= 1.844e18 (FLT_LARGE, kernels/common/ray.h) for every active
/// lane, and a float ray past it is of no use anyway.
constexpr float kEmbreeLargest = 1.844e18f;

/// Whether Embree may trace the ray: origin and direction components within kEmbreeLargest
/// (false for ±inf and NaN) and 0 <= tnear <= tfar (RTCRay: "the ray segment must be in the
/// range [0, ∞]"; false when either is NaN). 0/1, without branches, so lane loops vectorise.
inline int traceableRay(float ox, float oy, float oz, float dx, float dy, float dz, float tnear,
                        float tfar) {
  const float m = kEmbreeLargest;
  return int(std::fabs(ox) <= m) & int(std::fabs(oy) <= m) & int(std::fabs(oz) <= m) &
         int(std::fabs(dx) <= m) & int(std::fabs(dy) <= m) & int(std::fabs(dz) <= m) &
         int(tnear >= 0.0f) & int(tnear <= tfar);
}

/// The gate of every packet Embree traces (intersect<N>, the visibility's rtcOccluded16, the
/// baseline): lane k stays active (valid[k] = −1) only when it was (valid[k] != 0) and its
/// ray is traceableRay; every other lane gets valid[k] = 0 and the empty segment tnear 1,
/// tfar 0. Embree needs both. Its packet kernels assert that every active lane holds a valid
/// ray (Debian's Embree is built with assertions: an abort). And a device without native
/// kernels of the packet's width (rtcIntersect16 without AVX-512, rtcIntersect8 on SSE4.2)
/// traces the packet as a ray stream, which ignores the mask and skips only the lanes whose
/// tfar < tnear (RTCRay, rtcIntersectNM): a masked lane holding a NaN ray reached the
/// assertion that way. Returns the active lanes.
template <int N>
int sealLanes(int* __restrict valid, const RayLanes& l) {
  // Locals: the stores could otherwise alias the lane pointers and force reloads every lane.
  const float *ox = l.orgX, *oy = l.orgY, *oz = l.orgZ, *dx = l.dirX, *dy = l.dirY, *dz = l.dirZ;
  float* __restrict tnear = l.tnear, * __restrict tfar = l.tfar;
  int active = 0;
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {
    const int live = int(valid[k] != 0) &
                     traceableRay(ox[k], oy[k], oz[k], dx[k], dy[k], dz[k], tnear[k], tfar[k]);
    valid[k] = -live;
    tnear[k] = live ? tnear[k] : 1.0f;
    tfar[k] = live ? tfar[k] : 0.0f;
    active += live;
  }
  return active;
}

/// sealLanes for a packet whose active lanes already passed traceableRay (the frame loop's
/// selectLanes): only the masked lanes get the empty segment, without testing any ray again.
/// Returns the active lanes.
template <int N>
int sealMaskedLanes(const int* __restrict valid, const RayLanes& l) {
  float* __restrict tnear = l.tnear, * __restrict tfar = l.tfar;
  int active = 0;
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {
    const int live = int(valid[k] != 0);
    tnear[k] = live ? tnear[k] : 1.0f;
    tfar[k] = live ? tfar[k] : 0.0f;
    active += live;
  }
  return active;
}

/// A test seam: when set, called with every packet just as Embree receives it (after
/// sealLanes), from the thread that traces it. Set it only while nothing renders.
using PacketObserver = void (*)(int width, const int* valid, const RayLanes& rays);
inline std::atomic<PacketObserver> packetObserver{nullptr};

/// Calls the packet observer, if any, on a sealed packet.
inline void observePacket(int width, const int* valid, const RayLanes& rays) {
  if (const PacketObserver o = packetObserver.load(std::memory_order_relaxed))
    o(width, valid, rays);
}

/// rtcIntersectN for the packet width; `valid` is Embree's −1/0 lane mask (for N = 1, which
/// traces its one ray as the single active lane of rtcIntersect4, valid[0]). The packet first
/// passes sealLanes, so `valid` and the segments of the lanes it clears change: a lane whose
/// ray Embree cannot take comes back inactive, with its hit untouched.
/// `activeTraceable`: the caller vouches that every active lane passed traceableRay, so only
/// the masked lanes are sealed (sealMaskedLanes).
template <int N>
void intersect(RTCScene scene, RTCIntersectContext* ctx, int* valid, typename PacketOf<N>::type& p,
               bool activeTraceable = false) {
  const RayLanes lanes = rayLanes<N>(p);
  const int active =
      activeTraceable ? sealMaskedLanes<N>(valid, lanes) : sealLanes<N>(valid, lanes);
  observePacket(N, valid, lanes);
  if (active == 0) return;
  if constexpr (N == 1) {
    // One ray per call, but through the 4-wide kernel with one active lane: rtcIntersect1
    // breaks ties between coincident triangles differently from the packet kernels (seen on
    // the crown), and every packet width must give the same image.
    alignas(16) RTCRayHit4 q;
    alignas(16) const int one[4] = {-1, 0, 0, 0};
    q.ray.org_x[0] = p.ray.org_x, q.ray.org_y[0] = p.ray.org_y, q.ray.org_z[0] = p.ray.org_z;
    q.ray.dir_x[0] = p.ray.dir_x, q.ray.dir_y[0] = p.ray.dir_y, q.ray.dir_z[0] = p.ray.dir_z;
    q.ray.tnear[0] = p.ray.tnear, q.ray.tfar[0] = p.ray.tfar, q.ray.time[0] = p.ray.time;
    q.ray.mask[0] = p.ray.mask, q.ray.id[0] = p.ray.id, q.ray.flags[0] = p.ray.flags;
    q.hit.geomID[0] = RTC_INVALID_GEOMETRY_ID;
    q.hit.instID[0][0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect4(one, scene, ctx, &q);
    p.ray.tfar = q.ray.tfar[0];
    p.hit.Ng_x = q.hit.Ng_x[0], p.hit.Ng_y = q.hit.Ng_y[0], p.hit.Ng_z = q.hit.Ng_z[0];
    p.hit.u = q.hit.u[0], p.hit.v = q.hit.v[0];
    p.hit.primID = q.hit.primID[0], p.hit.geomID = q.hit.geomID[0];
    p.hit.instID[0] = q.hit.instID[0][0];
  } else if constexpr (N == 4) {
    rtcIntersect4(valid, scene, ctx, &p);
  } else if constexpr (N == 8) {
    rtcIntersect8(valid, scene, ctx, &p);
  } else {
    rtcIntersect16(valid, scene, ctx, &p);
  }
}

}  // namespace aperture
