#pragma once
// Tracing a packet against a Scene: Embree's call, then the scene's own hit conventions.
#include <cstddef>
#include <type_traits>

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

/// An intersection context whose filter hands every hit to `collector` and rejects it, so that
/// traversal goes on to the ray's tfar: one traversal meets every surface along the ray (on a
/// scene built with BuildOptions::contextFilter). `collector(args, i)` reads hit i of the
/// filter's arguments (RTCRayN_* and RTCHitN_*, as Embree reports them: chunks not resolved);
/// a lane is the ray's id, since Embree may pass the filter one ray of a packet or a copy of
/// it. Pass &base to intersectScene.
template <class Collector>
struct CollectingContext {
  RTCIntersectContext base;
  Collector collector;

  explicit CollectingContext(const Collector& c = Collector()) : collector(c) {
    static_assert(
        std::is_standard_layout<CollectingContext>::value && offsetof(CollectingContext, base) == 0,
        "Embree passes &base back to the filter");
    rtcInitIntersectContext(&base);
    base.filter = collectAndReject;
  }

 private:
  static void collectAndReject(const RTCFilterFunctionNArguments* args) {
    auto* ctx = reinterpret_cast<CollectingContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
      if (args->valid[i] == 0) continue;
      args->valid[i] = 0;
      ctx->collector(args, i);
    }
  }
};

}  // namespace aperture
