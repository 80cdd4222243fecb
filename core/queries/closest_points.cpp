#include "core/queries/closest_points.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/engine/packet.h"
#include "core/queries/morton_order.h"
#include "core/queries/world_triangles.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace aperture {

namespace {

using glm::dvec3;

dvec3 load(const double* v) { return {v[0], v[1], v[2]}; }

/// Closest point of segment [a, b] to p and the parameter along it.
double closestOnSegment(const dvec3& p, const dvec3& a, const dvec3& b, dvec3& q) {
  const dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  q = a + t * ab;
  return t;
}

/// A degenerate triangle (its points on a line or one point): the closest of its edges.
TrianglePoint closestOnEdges(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c) {
  dvec3 q;
  TrianglePoint best{};
  double bestD2 = std::numeric_limits<double>::infinity();
  const auto consider = [&](const dvec3& from, const dvec3& to, int i, int j) {
    const double t = closestOnSegment(p, from, to, q);
    const double d2 = glm::dot(p - q, p - q);
    if (!(d2 < bestD2)) return;
    bestD2 = d2;
    double w[3] = {0, 0, 0};
    w[i] = 1 - t, w[j] = t;
    best = {q.x, q.y, q.z, w[0], w[1], w[2]};
  };
  consider(a, b, 0, 1);
  consider(b, c, 1, 2);
  consider(c, a, 2, 0);
  return best;
}

TrianglePoint pointOf(const dvec3& q, double wa, double wb, double wc) {
  return {q.x, q.y, q.z, wa, wb, wc};
}

}  // namespace

// The Voronoi regions of the triangle's vertices, edges and face, tested in that order with
// dot products of the edges and the point (Ericson, Real-Time Collision Detection, 5.1.5).
TrianglePoint closestPointOnTriangle(const double* pp, const double* pa, const double* pb,
                                     const double* pc) {
  const dvec3 p = load(pp), a = load(pa), b = load(pb), c = load(pc);
  const dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return pointOf(a, 1, 0, 0);
  const dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return pointOf(b, 0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return pointOf(a + v * ab, 1 - v, v, 0);
  }
  const dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return pointOf(c, 0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return pointOf(a + w * ac, 1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return pointOf(b + w * (c - b), 0, 1 - w, w);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0) || !std::isfinite(sum)) return closestOnEdges(p, a, b, c);
  const double v = vb / sum, w = vc / sum;
  return pointOf(a + ab * v + ac * w, 1 - v - w, v, w);
}

namespace {

/// Shared by every query of one closestPoints call.
struct QueryScene {
  const Scene* scene = nullptr;
  std::vector<WorldObject> objects;  ///< per object (worldObjects)
  std::vector<char> identity;        ///< per object: worldFromMesh is the identity
  glm::dvec3 origin{0.0};            ///< Scene::renderOrigin: render space = world − origin

  /// World position of corner `corner` of the stored triangle `tri` of object `object`
  /// (anchor + position where the object is not moved, without the matrix).
  dvec3 corner(unsigned object, uint32_t tri, int corner) const {
    const WorldObject& o = objects[object];
    const size_t v = o.mesh->indices[3 * size_t(tri) + size_t(corner)];
    return identity[object] ? o.anchor + dvec3(o.mesh->vertex(v)) : o.vertex(v);
  }
};

/// One query point's search: its world position and the best triangle so far.
struct QueryState {
  const QueryScene* qs;
  dvec3 p;
  /// Added to a distance to make the query radius Embree culls with: the query point's float
  /// rounding and the float placement of instanced triangles (see radiusFor).
  double slack;
  double bestD2 = std::numeric_limits<double>::infinity();
  unsigned object = RTC_INVALID_GEOMETRY_ID;
  uint32_t prim = 0;  ///< Embree's primID on the object (chunks resolved)
  TrianglePoint point{};

  float radiusFor(double d2) const {
    const double r = (std::sqrt(d2) + slack) * (1 + 1e-6);
    return std::nextafter(float(r), std::numeric_limits<float>::infinity());
  }
  /// Makes triangle `prim` of `object` the best so far if it is closer (or as close and first
  /// in (object, primId) order); true when it did.
  bool consider(unsigned obj, uint32_t pr) {
    const uint32_t tri = qs->scene->meshTriangle(obj, pr);
    const dvec3 a = qs->corner(obj, tri, 0), b = qs->corner(obj, tri, 1),
                c = qs->corner(obj, tri, 2);
    const double pp[3] = {p.x, p.y, p.z};
    const double va[3] = {a.x, a.y, a.z}, vb[3] = {b.x, b.y, b.z}, vc[3] = {c.x, c.y, c.z};
    const TrianglePoint q = closestPointOnTriangle(pp, va, vb, vc);
    const dvec3 d = p - dvec3(q.x, q.y, q.z);
    const double d2 = glm::dot(d, d);
    if (d2 > bestD2 || (d2 == bestD2 && !winsTie(obj, pr))) return false;
    bestD2 = d2, object = obj, prim = pr, point = q;
    return true;
  }
  /// Whether (object, prim) comes before the best so far among triangles at the same distance.
  bool winsTie(unsigned obj, uint32_t pr) const {
    const Scene& s = *qs->scene;
    if (obj != object) return obj < object;
    return s.sourcePrimId(obj, pr) < s.sourcePrimId(object, prim);
  }
};

bool onCandidate(RTCPointQueryFunctionArguments* args) {
  auto* st = static_cast<QueryState*>(args->userPtr);
  const Scene& scene = *st->qs->scene;
  unsigned geom = args->geomID, prim = args->primID;
  unsigned inst =
      args->context->instStackSize > 0 ? args->context->instID[0] : RTC_INVALID_GEOMETRY_ID;
  if (scene.hasChunks()) scene.resolveChunkHits(&geom, &prim, &inst, 1);
  if (!st->consider(inst == RTC_INVALID_GEOMETRY_ID ? geom : inst, prim)) return false;
  const float r = st->radiusFor(st->bestD2);
  if (!(r < args->query->radius)) return false;
  args->query->radius = r;
  return true;
}

QueryScene queryScene(const Scene& scene) {
  QueryScene qs;
  qs.scene = &scene;
  qs.origin = scene.renderOrigin();
  WorldObjects world = worldObjects(scene);
  if (world.triangles == 0) throw Error("closest points: the scene holds no triangle");
  qs.objects = std::move(world.objects);
  for (const WorldObject& o : qs.objects) qs.identity.push_back(o.worldFromMesh == glm::dmat4(1.0));
  return qs;
}

/// Fills the results of query k as "no answer".
void storeNothing(ClosestPoints& out, size_t k) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int a = 0; a < 3; ++a)
    out.points[3 * k + size_t(a)] = out.barycentric[3 * k + size_t(a)] = nan;
  out.distance[k] = nan;
  out.primId[k] = out.geomId[k] = out.instance[k] = ClosestPoints::kNoPrim;
}

void storeFound(const Scene& scene, const QueryState& st, ClosestPoints& out, size_t k) {
  const TrianglePoint& q = st.point;
  out.points[3 * k] = q.x, out.points[3 * k + 1] = q.y, out.points[3 * k + 2] = q.z;
  out.barycentric[3 * k] = q.wa, out.barycentric[3 * k + 1] = q.wb,
                      out.barycentric[3 * k + 2] = q.wc;
  out.distance[k] = std::sqrt(st.bestD2);
  out.primId[k] = scene.sourcePrimId(st.object, st.prim);
  out.geomId[k] = st.object;
  const Mesh& mesh = scene.objectMesh(st.object);
  const uint32_t tri = scene.meshTriangle(st.object, st.prim);
  out.instance[k] =
      scene.objectIds(st.object).instance + (mesh.faceGroups.empty() ? 0u : mesh.faceGroups[tri]);
}

/// The answer of a nearby query, whose triangle starts the next search: its distance bounds
/// the search radius from the start, so Embree culls most of the BVH at once.
struct Seed {
  unsigned object = RTC_INVALID_GEOMETRY_ID;
  uint32_t prim = 0;
};

/// Searches query k, starting from `seed`'s triangle when it has one; false when its point
/// cannot be queried (not finite, or beyond Embree's float range in render space).
bool searchOne(const QueryScene& qs, const double* world, const Seed& seed, QueryState& st) {
  const dvec3 p = load(world);
  const dvec3 render = p - qs.origin;
  const float fx = float(render.x), fy = float(render.y), fz = float(render.z);
  const float m = kEmbreeLargest;
  if (!(std::fabs(fx) <= m && std::fabs(fy) <= m && std::fabs(fz) <= m)) return false;
  const dvec3 rounded(fx, fy, fz);
  st.p = p;
  const double extent = std::max({std::fabs(render.x), std::fabs(render.y), std::fabs(render.z)});
  st.slack = glm::length(render - rounded) + 1e-6 * extent;
  alignas(16) RTCPointQuery query;
  query.x = fx, query.y = fy, query.z = fz;
  query.time = 0.0f;
  query.radius = std::numeric_limits<float>::infinity();
  if (seed.object != RTC_INVALID_GEOMETRY_ID && st.consider(seed.object, seed.prim))
    query.radius = st.radiusFor(st.bestD2);
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(qs.scene->handle(), &query, &context, onCandidate, &st);
  return st.object != RTC_INVALID_GEOMETRY_ID;
}

/// The box of the finite points of `points` (lo > hi when there is none).
void finiteBox(const double* points, size_t count, dvec3& lo, dvec3& hi) {
  lo = dvec3(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t k = 0; k < count; ++k) {
    const dvec3 p = load(points + 3 * k);
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
      lo = glm::min(lo, p), hi = glm::max(hi, p);
  }
  if (lo.x > hi.x) lo = hi = dvec3(0.0);
}

}  // namespace

ClosestPoints closestPoints(const Scene& scene, const double* points, size_t count) {
  const QueryScene qs = queryScene(scene);
  ClosestPoints out;
  out.points.resize(3 * count);
  out.barycentric.resize(3 * count);
  out.distance.resize(count);
  out.primId.resize(count);
  out.geomId.resize(count);
  out.instance.resize(count);
  // Queries run in Morton order over the points' box, each seeded with the answer of the one
  // before it in its chunk.
  dvec3 lo, hi;
  finiteBox(points, count, lo, hi);
  const std::vector<size_t> order = mortonOrder(points, count, lo, hi);
  constexpr size_t kChunk = 1024;
  std::vector<size_t> skipped((count + kChunk - 1) / kChunk, 0);
  parallelForChunks(count, kChunk, [&](size_t c, size_t first, size_t last) {
    Seed seed;
    for (size_t i = first; i < last; ++i) {
      const size_t k = order[i];
      QueryState st{&qs, dvec3(0.0), 0.0};
      if (searchOne(qs, points + 3 * k, seed, st)) {
        storeFound(scene, st, out, k);
        seed = {st.object, st.prim};
      } else {
        storeNothing(out, k);
        ++skipped[c];
      }
    }
  });
  for (size_t s : skipped) out.nonFinite += s;
  return out;
}

}  // namespace aperture
