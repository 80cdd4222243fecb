#include "core/engine/layers.h"

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

void checkLayerCount(int layers, const std::string& source) {
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

/// One surface along a ray, with Embree's raw ids (instID: RTC_INVALID_GEOMETRY_ID when the
/// mesh is attached directly).
struct LayerHit {
  float t;
  unsigned primID, geomID, instID;

  bool samePrimitive(const LayerHit& o) const {
    return primID == o.primID && geomID == o.geomID && instID == o.instID;
  }
  /// The object the Z/T/geomID AOVs name: the instance, or the directly attached geometry.
  unsigned object() const { return instID == RTC_INVALID_GEOMETRY_ID ? geomID : instID; }
  /// Order along the ray: t, then object and primID, so ties come out the same at every
  /// packet width whatever order Embree visits them in.
  bool before(const LayerHit& o) const {
    if (t != o.t) return t < o.t;
    if (object() != o.object()) return object() < o.object();
    return primID < o.primID;
  }
};

/// The hits of one lane, nearest first, at most `capacity`.
struct LaneLayers {
  LayerHit hit[kMaxLayers];
  int count = 0;

  void push(const LayerHit& h) { hit[count++] = h; }
  bool contains(const LayerHit& h) const {
    for (int i = 0; i < count; ++i)
      if (hit[i].samePrimitive(h)) return true;
    return false;
  }
  /// Inserts `h` in order, keeping the `capacity` nearest. Returns the index it went to, or
  /// -1 when it was not kept (a duplicate, or beyond the nearest `capacity`).
  int insert(const LayerHit& h, int capacity) {
    if (contains(h)) return -1;
    if (count == capacity && !h.before(hit[count - 1])) return -1;
    int i = count < capacity ? count++ : capacity - 1;
    for (; i > 0 && h.before(hit[i - 1]); --i) hit[i] = hit[i - 1];
    hit[i] = h;
    return i;
  }
};

/// A packet of its own for the layer passes (the caller's keeps its first hits).
template <int N>
struct LayerPacket : PacketBuffers<N> {
  float tfar[N];  ///< each lane's tfar as the camera generated it (a clip's far end)
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
/// traceByFilter sets: Embree may pass the filter a copy of the ray, or one ray of a packet
/// with the others masked off). Rejects the hit so traversal goes on, except when it became
/// the K-th nearest of a full list: accepting it then moves the ray's tfar to it, and Embree
/// skips what lies beyond.
void collectHit(const RTCFilterFunctionNArguments* args) {
  const auto* ctx = reinterpret_cast<const FilterContext*>(args->context);
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] == 0) continue;
    LayerHit h{RTCRayN_tfar(args->ray, n, i), RTCHitN_primID(args->hit, n, i),
               RTCHitN_geomID(args->hit, n, i), RTCHitN_instID(args->hit, n, i, 0)};
    if (ctx->scene->hasChunks()) ctx->scene->resolveChunkHits(&h.geomID, &h.primID, &h.instID, 1);
    LaneLayers& lane = ctx->lanes[RTCRayN_id(args->ray, n, i)];
    const int at = lane.insert(h, ctx->capacity);
    const bool lastOfFull = at == ctx->capacity - 1;
    if (!lastOfFull) args->valid[i] = 0;
  }
}

/// Regenerates the packet's rays and keeps the lanes whose first ray hit.
template <int N>
void prepareRays(const LayerPlan& plan, const PacketRequest& req, const int* hit,
                 LayerPacket<N>& lp) {
  plan.camera.generate(req, lp.lanes, lp.valid);
  for (int k = 0; k < N; ++k) {
    lp.valid[k] = hit[k] ? -1 : 0;
    lp.tfar[k] = lp.lanes.tfar[k];
    lp.lanes.id[k] = unsigned(k);
  }
}

/// Filter: one traversal collects the K nearest hits of each lane.
template <int N>
void traceByFilter(const LayerPlan& plan, LayerPacket<N>& lp) {
  FilterContext ctx;
  rtcInitIntersectContext(&ctx.base);
  ctx.base.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  ctx.base.filter = collectHit;
  ctx.lanes = lp.found;
  ctx.capacity = plan.layers;
  ctx.scene = &plan.scene;
  clearHits<N>(lp.packet);
  intersectScene<N>(plan.scene, &ctx.base, lp.valid, lp.packet);
}

/// Retrace: from the first hit, trace the lanes short of K again just past their last hit.
template <int N>
void traceByRetracing(const LayerPlan& plan, const LayerHit* first, LayerPacket<N>& lp) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  const float inf = std::numeric_limits<float>::infinity();
  float lastT[N];
  int active = 0;
  for (int k = 0; k < N; ++k) {
    if (lp.valid[k] == 0) continue;
    lp.found[k].push(first[k]);
    lastT[k] = first[k].t;
    if (plan.layers == 1) lp.valid[k] = 0;
    active += lp.valid[k] != 0;
  }
  // Each pass either adds a layer to a lane or moves its tnear on by at least one ulp (when
  // Embree reports the previous primitive again), so this ends; the bound is a safeguard.
  for (int pass = 0; active > 0 && pass < 4 * kMaxLayers; ++pass) {
    for (int k = 0; k < N; ++k) {
      lp.lanes.tnear[k] = lp.valid[k] ? std::nextafter(lastT[k], inf) : 0.0f;
      lp.lanes.tfar[k] = lp.tfar[k];
    }
    clearHits<N>(lp.packet);
    intersectScene<N>(plan.scene, &ctx, lp.valid, lp.packet);
    active = 0;
    for (int k = 0; k < N; ++k) {
      if (lp.valid[k] == 0) continue;
      LaneLayers& lane = lp.found[k];
      if (lp.hits.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
        lp.valid[k] = 0;
        continue;
      }
      const LayerHit h{lp.hits.tfar[k], lp.hits.primID[k], lp.hits.geomID[k], lp.hits.instID[k]};
      lastT[k] = h.t;
      if (!h.samePrimitive(lane.hit[lane.count - 1])) lane.push(h);
      if (lane.count == plan.layers) lp.valid[k] = 0;
      active += lp.valid[k] != 0;
    }
  }
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
void traceLayers(const LayerPlan& plan, const PacketRequest& req, const HitLanes& first,
                 const int* hit) {
  LayerPacket<N> lp;
  prepareRays<N>(plan, req, hit, lp);
  LayerHit firstHit[N];
  for (int k = 0; k < N; ++k)
    firstHit[k] = {first.tfar[k], first.primID[k], first.geomID[k], first.instID[k]};
  if (plan.layers > 1) {
    if (plan.method == LayerMethod::Filter)
      traceByFilter<N>(plan, lp);
    else
      traceByRetracing<N>(plan, firstHit, lp);
  }
  for (int k = 0; k < N; ++k)
    if (hit[k]) storeLane<N>(plan, req, lp, k, firstHit[k]);
}

template void traceLayers<1>(const LayerPlan&, const PacketRequest&, const HitLanes&, const int*);
template void traceLayers<4>(const LayerPlan&, const PacketRequest&, const HitLanes&, const int*);
template void traceLayers<8>(const LayerPlan&, const PacketRequest&, const HitLanes&, const int*);
template void traceLayers<16>(const LayerPlan&, const PacketRequest&, const HitLanes&, const int*);

}  // namespace aperture
