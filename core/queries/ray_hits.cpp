#include "core/queries/ray_hits.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "core/engine/intersect_scene.h"
#include "core/engine/packet.h"
#include "core/util/parallel.h"

namespace aperture {

namespace {

/// One surface along a ray, in the scene's terms (chunks resolved).
struct RayHit {
  float t;
  unsigned object;
  uint32_t prim;  ///< Embree's primID on the object
};

/// The ray in render space, or false when Embree cannot take it.
bool renderRay(const Scene& scene, const double* o, const double* d, RTCRayHit& p) {
  const glm::dvec3 org = glm::dvec3(o[0], o[1], o[2]) - scene.renderOrigin();
  p.ray.org_x = float(org.x), p.ray.org_y = float(org.y), p.ray.org_z = float(org.z);
  p.ray.dir_x = float(d[0]), p.ray.dir_y = float(d[1]), p.ray.dir_z = float(d[2]);
  p.ray.time = 0.0f;
  p.ray.mask = 0xFFFFFFFFu, p.ray.id = 0, p.ray.flags = 0;
  const bool nonZero = p.ray.dir_x != 0.0f || p.ray.dir_y != 0.0f || p.ray.dir_z != 0.0f;
  return nonZero && traceableRay(p.ray.org_x, p.ray.org_y, p.ray.org_z, p.ray.dir_x, p.ray.dir_y,
                                 p.ray.dir_z, 0.0f, 1.0f);
}

/// Calls onHit(RayHit) for every surface along the ray, nearest first; false when the ray
/// cannot be traced.
template <class OnHit>
bool forEachHit(const Scene& scene, const double* origin, const double* direction,
                const OnHit& onHit) {
  RTCRayHit p;
  if (!renderRay(scene, origin, direction, p)) return false;
  const float inf = std::numeric_limits<float>::infinity();
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  float tnear = 0.0f;
  RayHit last{-1.0f, RTC_INVALID_GEOMETRY_ID, 0};
  // Each pass either finds a new triangle or moves tnear on by at least one float, so this
  // ends: at the latest when tnear passes the scene.
  for (;;) {
    p.ray.tnear = tnear, p.ray.tfar = inf;
    clearHits<1>(p);
    int valid = -1;
    intersectScene<1>(scene, &ctx, &valid, p, true);
    if (p.hit.geomID == RTC_INVALID_GEOMETRY_ID) return true;
    const unsigned object =
        p.hit.instID[0] == RTC_INVALID_GEOMETRY_ID ? p.hit.geomID : p.hit.instID[0];
    const RayHit h{p.ray.tfar, object, p.hit.primID};
    if (h.object != last.object || h.prim != last.prim) onHit(h);
    last = h;
    tnear = std::nextafter(h.t, inf);
  }
}

/// countByFilter's collector: the t of every hit.
struct HitDistances {
  std::vector<float>* t;
  void operator()(const RTCFilterFunctionNArguments* args, unsigned i) const {
    t->push_back(RTCRayN_tfar(args->ray, args->N, i));
  }
};

/// The number of hits forEachHit reports, in one traversal of a scene built with
/// BuildOptions::contextFilter: the number of distinct t among every hit along the ray (the
/// retrace moves tnear to the next float past each hit, so it finds each distinct t once, and
/// one triangle has one t). `t` is scratch space. False when the ray cannot be traced.
bool countByFilter(const Scene& scene, const double* origin, const double* direction,
                   std::vector<float>& t, uint32_t& count) {
  RTCRayHit p;
  count = 0;
  if (!renderRay(scene, origin, direction, p)) return false;
  CollectingContext<HitDistances> ctx(HitDistances{&t});
  t.clear();
  p.ray.tnear = 0.0f, p.ray.tfar = std::numeric_limits<float>::infinity();
  clearHits<1>(p);
  int valid = -1;
  intersectScene<1>(scene, &ctx.base, &valid, p, true);
  std::sort(t.begin(), t.end());
  count = uint32_t(std::unique(t.begin(), t.end()) - t.begin());
  return true;
}

constexpr size_t kRayChunk = 256;

}  // namespace

std::vector<uint32_t> countIntersections(const Scene& scene, const double* origins,
                                         const double* directions, size_t count,
                                         size_t* nonFinite) {
  std::vector<uint32_t> counts(count, 0);
  std::vector<size_t> skipped((count + kRayChunk - 1) / kRayChunk, 0);
  const bool byFilter = scene.options().contextFilter;
  parallelForChunks(count, kRayChunk, [&](size_t c, size_t first, size_t last) {
    std::vector<float> t;
    for (size_t k = first; k < last; ++k) {
      uint32_t n = 0;
      const bool traced = byFilter ? countByFilter(scene, origins + 3 * k, directions + 3 * k, t, n)
                                   : forEachHit(scene, origins + 3 * k, directions + 3 * k,
                                                [&](const RayHit&) { ++n; });
      if (!traced) ++skipped[c];
      counts[k] = n;
    }
  });
  if (nonFinite) {
    *nonFinite = 0;
    for (size_t s : skipped) *nonFinite += s;
  }
  return counts;
}

RayHitList listIntersections(const Scene& scene, const double* origins, const double* directions,
                             size_t count) {
  // Each chunk of rays collects its hits on its own; the chunks are then joined in order.
  const size_t chunks = (count + kRayChunk - 1) / kRayChunk;
  std::vector<std::vector<RayHit>> hits(chunks);
  std::vector<std::vector<uint32_t>> perRay(chunks);
  std::vector<size_t> skipped(chunks, 0);
  parallelForChunks(count, kRayChunk, [&](size_t c, size_t first, size_t last) {
    for (size_t k = first; k < last; ++k) {
      uint32_t n = 0;
      if (!forEachHit(scene, origins + 3 * k, directions + 3 * k, [&](const RayHit& h) {
            hits[c].push_back(h);
            ++n;
          }))
        ++skipped[c];
      perRay[c].push_back(n);
    }
  });
  RayHitList out;
  out.offsets.reserve(count + 1);
  out.offsets.push_back(0);
  for (size_t c = 0; c < chunks; ++c) {
    for (uint32_t n : perRay[c]) out.offsets.push_back(out.offsets.back() + n);
    for (const RayHit& h : hits[c]) {
      out.t.push_back(double(h.t));
      out.primId.push_back(scene.sourcePrimId(h.object, h.prim));
      out.geomId.push_back(h.object);
    }
    out.nonFinite += skipped[c];
  }
  return out;
}

}  // namespace aperture
