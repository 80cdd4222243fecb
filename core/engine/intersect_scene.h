#pragma once
// Tracing a packet against a Scene: Embree's call, then the scene's own hit conventions.
#include "core/engine/packet.h"
#include "core/engine/scene.h"

namespace aperture {

/// Hits reported through a chunk's instance (BuildOptions::bvhChunkTriangles) become hits on
/// the chunked object itself (Scene::resolveChunkHits).
template <int N>
void resolveChunkHits(const Scene& scene, typename PacketOf<N>::type& p) {
  if constexpr (N == 1)
    scene.resolveChunkHits(&p.hit.geomID, &p.hit.primID, &p.hit.instID[0], 1);
  else
    scene.resolveChunkHits(p.hit.geomID, p.hit.primID, p.hit.instID[0], N);
}

/// intersect<N> on `scene`, with every hit in the scene's terms: objects built in chunks
/// report the geomID and primID they have when attached whole. Every trace of a Scene goes
/// through here; intersect<N> clears the lanes of `valid` whose rays Embree cannot take
/// (`activeTraceable`: the caller already tested the active lanes, intersect<N>).
template <int N>
void intersectScene(const Scene& scene, RTCIntersectContext* ctx, int* valid,
                    typename PacketOf<N>::type& p, bool activeTraceable = false) {
  intersect<N>(scene.handle(), ctx, valid, p, activeTraceable);
  if (scene.hasChunks()) resolveChunkHits<N>(scene, p);
}

}  // namespace aperture
