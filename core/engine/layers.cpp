#include "core/engine/layers.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>

#include "core/aov/aov_table.h"
#include "core/engine/intersect_scene.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

LayerMethod parseLayerMethod(const std::string& name) {
  for (LayerMethod m : {LayerMethod::Filter, LayerMethod::Retrace})
    if (name == layerMethodName(m)) return m;
  throw Error(cat("unknown layer method '", name, "'", didYouMean(name, {"filter", "retrace"}),
                  " (known: filter, retrace)"));
}

const char* layerMethodName(LayerMethod method) {
  return method == LayerMethod::Retrace ? "retrace" : "filter";
}

namespace {
/// setLayerMethod's choice; unset until called.
std::atomic<int> chosenMethod{-1};
}  // namespace

LayerMethod defaultLayerMethod() {
  const int chosen = chosenMethod.load(std::memory_order_relaxed);
  if (chosen >= 0) return LayerMethod(chosen);
  static const std::optional<std::string> fromEnvironment = []() -> std::optional<std::string> {
    const char* v = std::getenv("APERTURE_LAYERS_METHOD");
    if (v == nullptr || *v == '\0') return std::nullopt;
    return std::string(v);
  }();
  if (!fromEnvironment) return LayerMethod::Filter;
  try {
    return parseLayerMethod(*fromEnvironment);
  } catch (const Error& e) {
    throw Error(cat("APERTURE_LAYERS_METHOD: ", e.what()));
  }
}

void setLayerMethod(LayerMethod method) {
  chosenMethod.store(int(method), std::memory_order_relaxed);
}

void checkLayerCount(int layers, const char* source) {
  if (layers < 1 || layers > kMaxLayers)
    throw Error(cat(source, " ", layers, " must be in [1, ", kMaxLayers, "]"));
}

bool layersNeedContextFilter(const AovSet& aovs) {
  return aovs.layers > 0 && defaultLayerMethod() == LayerMethod::Filter;
}

namespace {

/// The first value of the layered hits of the AOV row `row` ("layers.depth" for "depth") in
/// `px`; Error when it has no storage.
void* layerStorage(const FramePixels& px, const char* row) {
  const std::string name = layerAovName(*findAovRow(row));
  const PixelChannel* c = px.find(name);
  if (!c || !c->data) throw Error(cat("layered hits: the storage holds no '", name, "'"));
  return c->data;
}

}  // namespace

LayerPlan::LayerPlan(const Scene& scene_, const Camera& camera_, const FramePixels& px,
                     glm::vec3 eye_, glm::vec3 axis_, LayerMethod method_)
    : scene(scene_),
      camera(camera_),
      depth(static_cast<float*>(layerStorage(px, "depth"))),
      distance(static_cast<float*>(layerStorage(px, "distance"))),
      primId(static_cast<uint32_t*>(layerStorage(px, "primid"))),
      geomId(static_cast<uint32_t*>(layerStorage(px, "geomid"))),
      pixelCount(px.pixelCount()),
      eye(eye_),
      axis(axis_),
      method(scene_.options().contextFilter ? method_ : LayerMethod::Retrace),
      layers(px.aovs.layers),
      imageWidth(px.width) {
  checkLayerCount(layers, "framebuffer layers");
}

LayerPlan::LayerPlan(const Scene& scene_, const Camera& camera_, Framebuffer& fb, glm::vec3 eye_,
                     glm::vec3 axis_, LayerMethod method_)
    : LayerPlan(scene_, camera_, framePixelsOf(fb), eye_, axis_, method_) {}

namespace {

/// The t at or past which the next surface of a chain may begin, after one at t.
float nextSurfaceStart(float t, float separation) {
  return std::max(std::nextafter(t, std::numeric_limits<float>::infinity()), t + separation);
}

/// A packet of its own for the layer passes (the caller's keeps its first hits).
template <int N>
struct LayerPacket : PacketBuffers<N> {
  LaneLayers found[N];
};

/// The intersection context of the Filter method. Embree hands the filter the context
/// pointer it was given, so the per-lane lists ride behind the RTCIntersectContext that
/// must come first.
struct FilterContext {
  RTCIntersectContext base;
  LaneLayers* lanes;
  int capacity;
  const Scene* scene;  // its chunk hits are resolved before they are recorded
};
static_assert(offsetof(FilterContext, base) == 0, "Embree passes &base back to the filter");

/// Context filter: records every hit in its lane's list (the lane is the ray's id, which
/// collectNearest sets: Embree may pass the filter a copy of the ray, or one ray of a packet
/// with the others masked off). Rejects the hit so traversal goes on, except when it became
/// the K-th nearest of a full list: accepting it then moves the ray's tfar to it, and Embree
/// skips what lies beyond.
void collectHit(const RTCFilterFunctionNArguments* args) {
  const auto* ctx = reinterpret_cast<const FilterContext*>(args->context);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] == 0) continue;
    LayerHit h{RTCRayN_tfar(args->ray, n, i),
               glm::vec3(RTCHitN_Ng_x(args->hit, n, i), RTCHitN_Ng_y(args->hit, n, i),
                         RTCHitN_Ng_z(args->hit, n, i)),
               RTCHitN_primID(args->hit, n, i), RTCHitN_geomID(args->hit, n, i),
               RTCHitN_instID(args->hit, n, i, 0)};
    if (ctx->scene->hasChunks()) ctx->scene->resolveChunkHits(&h.geomID, &h.primID, &h.instID, 1);
    LaneLayers& lane = ctx->lanes[RTCRayN_id(args->ray, n, i)];
    const int at = lane.insert(h, ctx->capacity);
    const bool lastOfFull = at == ctx->capacity - 1;
    if (!lastOfFull) args->valid[i] = 0;
  }
}

/// One Filter traversal: the `capacity` nearest primitives along each lane of `valid` (a copy:
/// the gate may clear lanes) within the lanes' [tnear, tfar], into nearest[k].
template <int N>
void collectNearest(const Scene& scene, int capacity, PacketBuffers<N>& rays, const int* live,
                    LaneLayers* nearest) {
  alignas(64) int valid[N];
  for (int k = 0; k < N; ++k) {
    valid[k] = live[k];
    nearest[k].count = 0;
    rays.lanes.id[k] = unsigned(k);
  }
  FilterContext ctx;
  rtcInitIntersectContext(&ctx.base);
  ctx.base.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  ctx.base.filter = collectHit;
  ctx.lanes = nearest;
  ctx.capacity = capacity;
  ctx.scene = &scene;
  clearHits<N>(rays.packet);
  intersectScene<N>(scene, &ctx.base, valid, rays.packet);
}

/// traceByFilter with a separation: the chain of surfaces each lane of `live` builds from the
/// 2K nearest primitives, traversing again past the last of them while the chain is short of K
/// and the list was full (more may lie beyond). `tfar`: the lanes' own.
template <int N>
void chainSurfaces(const Scene& scene, const SurfaceSearch& search, PacketBuffers<N>& rays,
                   const float* tfar, int* live, LaneLayers* found) {
  const int K = search.surfaces;
  const float separation = search.separation;
  const int capacity = std::min(kMaxLayers, 2 * K);
  LaneLayers nearest[N];
  // Each pass either ends a lane or moves its tnear past at least one primitive; the bound is
  // a safeguard.
  bool any = true;
  for (int pass = 0; any && pass < 4 * kMaxLayers; ++pass) {
    collectNearest<N>(scene, capacity, rays, live, nearest);
    any = false;
    for (int k = 0; k < N; ++k) {
      if (live[k] == 0) continue;
      const LaneLayers& raw = nearest[k];
      LaneLayers& chain = found[k];
      live[k] = 0;
      for (int i = 0; i < raw.count && chain.count < K; ++i)
        if (chain.count == 0 ||
            raw.hit[i].t >= nextSurfaceStart(chain.hit[chain.count - 1].t, separation))
          chain.push(raw.hit[i]);
      if (chain.count == K || raw.count < capacity) continue;
      const float from =
          std::max(std::nextafter(raw.hit[raw.count - 1].t, std::numeric_limits<float>::infinity()),
                   nextSurfaceStart(chain.hit[chain.count - 1].t, separation));
      if (!(from <= tfar[k])) continue;
      rays.lanes.tnear[k] = from;
      rays.lanes.tfar[k] = tfar[k];
      live[k] = -1;
      any = true;
    }
  }
}

/// Filter: the K nearest primitives of each lane in one traversal (separation 0), or the chain
/// of surfaces a separation apart (chainSurfaces).
template <int N>
void traceByFilter(const Scene& scene, const SurfaceSearch& search, PacketBuffers<N>& rays,
                   LaneLayers* found) {
  float tfar[N];
  int live[N];
  for (int k = 0; k < N; ++k) {
    tfar[k] = rays.lanes.tfar[k];
    live[k] = rays.valid[k] ? -1 : 0;
    found[k].count = 0;
  }
  if (search.separation <= 0) {
    // Every primitive is a surface: the K nearest, straight into found.
    collectNearest<N>(scene, search.surfaces, rays, live, found);
  } else {
    chainSurfaces<N>(scene, search, rays, tfar, live, found);
  }
  for (int k = 0; k < N; ++k) rays.lanes.tfar[k] = tfar[k];
}

/// The closest hit of each valid lane (a miss: count 0), into found[k] as its first surface.
template <int N>
void traceClosest(const Scene& scene, PacketBuffers<N>& rays, LaneLayers* found) {
  alignas(64) int valid[N];
  for (int k = 0; k < N; ++k) valid[k] = rays.valid[k] ? -1 : 0;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  clearHits<N>(rays.packet);
  intersectScene<N>(scene, &ctx, valid, rays.packet);
  const HitLanes& h = rays.hits;
  for (int k = 0; k < N; ++k) {
    found[k].count = 0;
    if (valid[k] == 0 || h.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
    found[k].push({h.tfar[k], glm::vec3(h.ngX[k], h.ngY[k], h.ngZ[k]), h.primID[k], h.geomID[k],
                   h.instID[k]});
  }
}

/// Retrace: from the first hit, trace the lanes short of K again from where the next surface
/// may begin (just past their last hit, or `separation` past it).
template <int N>
void traceByRetracing(const Scene& scene, const SurfaceSearch& search, PacketBuffers<N>& rays,
                      const LayerHit* first, LaneLayers* found) {
  float tfar[N];
  for (int k = 0; k < N; ++k) tfar[k] = rays.lanes.tfar[k];
  if (first == nullptr) {
    traceClosest<N>(scene, rays, found);
  } else {
    for (int k = 0; k < N; ++k) {
      found[k].count = 0;
      if (rays.valid[k]) found[k].push(first[k]);
    }
  }
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  float lastT[N];
  alignas(64) int valid[N];
  int active = 0;
  for (int k = 0; k < N; ++k) {
    valid[k] = found[k].count > 0 && found[k].count < search.surfaces ? -1 : 0;
    lastT[k] = found[k].count > 0 ? found[k].hit[0].t : 0.0f;
    active += valid[k] != 0;
  }
  // Each pass either adds a layer to a lane or moves its tnear on by at least one ulp (when
  // Embree reports the previous primitive again), so this ends; the bound is a safeguard.
  for (int pass = 0; active > 0 && pass < 4 * kMaxLayers; ++pass) {
    for (int k = 0; k < N; ++k) {
      rays.lanes.tnear[k] = valid[k] ? nextSurfaceStart(lastT[k], search.separation) : 0.0f;
      rays.lanes.tfar[k] = tfar[k];
    }
    clearHits<N>(rays.packet);
    intersectScene<N>(scene, &ctx, valid, rays.packet);
    active = 0;
    const HitLanes& h = rays.hits;
    for (int k = 0; k < N; ++k) {
      if (valid[k] == 0) continue;
      LaneLayers& lane = found[k];
      if (h.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
        valid[k] = 0;
        continue;
      }
      const LayerHit hit{h.tfar[k], glm::vec3(h.ngX[k], h.ngY[k], h.ngZ[k]), h.primID[k],
                         h.geomID[k], h.instID[k]};
      lastT[k] = hit.t;
      if (!hit.samePrimitive(lane.hit[lane.count - 1])) lane.push(hit);
      if (lane.count == search.surfaces) valid[k] = 0;
      active += valid[k] != 0;
    }
  }
  for (int k = 0; k < N; ++k) rays.lanes.tfar[k] = tfar[k];
}

/// Planar depth of a hit at t on lane k: (org − eye)·axis + t·(dir·axis), the same
/// expression in the same order as the frame loop's Z AOV, so layer 0 equals it bit for bit.
inline float planarDepth(const LayerPlan& plan, const RayLanes& l, int k, float t) {
  const glm::vec3 e = plan.eye, a = plan.axis;
  return (l.orgX[k] - e.x) * a.x + (l.orgY[k] - e.y) * a.y + (l.orgZ[k] - e.z) * a.z +
         t * (l.dirX[k] * a.x + l.dirY[k] * a.y + l.dirZ[k] * a.z);
}

/// Writes layer `layer` of pixel `px`.
void storeLayer(const LayerPlan& plan, size_t px, int layer, const LayerHit& h, float z) {
  const size_t at = size_t(layer) * plan.pixelCount + px;
  const unsigned object = h.object();
  plan.depth[at] = z;
  plan.distance[at] = h.t;
  plan.primId[at] =
      plan.scene.remapsPrimIds() ? plan.scene.sourcePrimId(object, h.primID) : h.primID;
  plan.geomId[at] = object;
}

/// Stores lane k's layers: the first hit, then the method's hits other than it, in order.
template <int N>
void storeLane(const LayerPlan& plan, const PacketRequest& req, const LayerPacket<N>& lp, int k,
               const LayerHit& first) {
  const LanePixel p = lanePixel(req.x0, req.y0, req.blockW, k);
  const size_t px = plan.pixelOffset + size_t(p.row) * size_t(plan.imageWidth) + size_t(p.column);
  storeLayer(plan, px, 0, first, planarDepth(plan, lp.lanes, k, first.t));
  const LaneLayers& lane = lp.found[k];
  int layer = 1;
  bool skippedFirst = false;
  for (int i = 0; i < lane.count && layer < plan.layers; ++i) {
    // Filter's list holds the first hit too (normally at index 0; after a tie in t,
    // possibly later): it is layer 0 already.
    if (!skippedFirst && lane.hit[i].samePrimitive(first)) {
      skippedFirst = true;
      continue;
    }
    storeLayer(plan, px, layer++, lane.hit[i], planarDepth(plan, lp.lanes, k, lane.hit[i].t));
  }
}

}  // namespace

template <int N>
void traceSurfaces(const Scene& scene, const SurfaceSearch& search, PacketBuffers<N>& rays,
                   const LayerHit* first, LaneLayers* found) {
  checkLayerCount(search.surfaces, "surfaces per ray");
  const bool filter = search.method == LayerMethod::Filter && scene.options().contextFilter;
  if (filter)
    traceByFilter<N>(scene, search, rays, found);
  else
    traceByRetracing<N>(scene, search, rays, first, found);
}

template <int N>
void traceLayers(const LayerPlan& plan, const PacketRequest& req, const HitLanes& first,
                 const int* hit) {
  LayerPacket<N> lp;
  plan.camera.generate(req, lp.lanes, lp.valid);
  LayerHit firstHit[N];
  for (int k = 0; k < N; ++k) {
    lp.valid[k] = hit[k] ? -1 : 0;
    firstHit[k] = {first.tfar[k], glm::vec3(first.ngX[k], first.ngY[k], first.ngZ[k]),
                   first.primID[k], first.geomID[k], first.instID[k]};
  }
  if (plan.layers > 1)
    traceSurfaces<N>(plan.scene, {plan.layers, 0.0f, plan.method}, lp, firstHit, lp.found);
  for (int k = 0; k < N; ++k)
    if (hit[k]) storeLane<N>(plan, req, lp, k, firstHit[k]);
}

template void traceSurfaces<1>(const Scene&, const SurfaceSearch&, PacketBuffers<1>&,
                               const LayerHit*, LaneLayers*);
template void traceSurfaces<4>(const Scene&, const SurfaceSearch&, PacketBuffers<4>&,
                               const LayerHit*, LaneLayers*);
template void traceSurfaces<8>(const Scene&, const SurfaceSearch&, PacketBuffers<8>&,
                               const LayerHit*, LaneLayers*);
template void traceSurfaces<16>(const Scene&, const SurfaceSearch&, PacketBuffers<16>&,
                                const LayerHit*, LaneLayers*);
template void traceLayers<1>(const LayerPlan&, const PacketRequest&, const HitLanes&, const int*);
template void traceLayers<4>(const LayerPlan&, const PacketRequest&, const HitLanes&, const int*);
template void traceLayers<8>(const LayerPlan&, const PacketRequest&, const HitLanes&, const int*);
template void traceLayers<16>(const LayerPlan&, const PacketRequest&, const HitLanes&, const int*);

}  // namespace aperture
