#pragma once
// Embree packet types by width, and RayLanes views into them.
#include <embree3/rtcore.h>

#include "core/engine/camera.h"

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

/// rtcIntersectN for the packet width; `valid` is Embree's −1/0 lane mask (unused for N = 1,
/// which traces its one ray as the single active lane of rtcIntersect4).
template <int N>
void intersect(RTCScene scene, RTCIntersectContext* ctx, const int* valid,
               typename PacketOf<N>::type& p) {
  if constexpr (N == 1) {
    // One ray per call, but through the 4-wide kernel with one active lane: rtcIntersect1
    // breaks ties between coincident triangles differently from the packet kernels (seen on
    // the crown), and every packet width must give the same image.
    (void)valid;
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
