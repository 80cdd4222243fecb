#include "core/queries/inside.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>

#include "core/engine/intersect_scene.h"
#include "core/engine/packet.h"
#include "core/queries/winding_number.h"
#include "core/queries/world_triangles.h"
#include "core/util/error.h"
#include "core/util/morton.h"
#include "core/util/parallel.h"
#include "core/util/spelling.h"

namespace aperture {

const char* insideMethodName(InsideMethod method) {
  switch (method) {
    case InsideMethod::Parity:
      return "parity";
    case InsideMethod::Winding:
      return "winding";
    default:
      return "automatic";
  }
}

InsideMethod parseInsideMethod(const std::string& name) {
  for (InsideMethod m : {InsideMethod::Parity, InsideMethod::Winding, InsideMethod::Automatic})
    if (name == insideMethodName(m)) return m;
  throw Error(cat("unknown inside method '", name, "'",
                  didYouMean(name, {"parity", "winding", "automatic"}),
                  " (known: parity, winding, automatic)"));
}

// ---------------------------------------------------------------------------------------------
// Closedness

namespace {

bool lessPosition(const glm::dvec3& a, const glm::dvec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

/// For each position, its id: positions that are equal get the same id.
std::vector<uint32_t> weldedIds(const std::vector<glm::dvec3>& positions) {
  std::vector<uint32_t> byPosition(positions.size());
  parallelFor(positions.size(), 1 << 16, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) byPosition[k] = uint32_t(k);
  });
  tbb::parallel_sort(byPosition.begin(), byPosition.end(), [&](uint32_t a, uint32_t b) {
    return lessPosition(positions[a], positions[b]);
  });
  std::vector<uint32_t> ids(positions.size());
  uint32_t id = 0;
  for (size_t k = 0; k < byPosition.size(); ++k) {
    if (k > 0 && lessPosition(positions[byPosition[k - 1]], positions[byPosition[k]])) ++id;
    ids[byPosition[k]] = id;
  }
  return ids;
}

/// The scene's triangles as 3 welded vertex ids each (objects in order, each object's
/// triangles as its BVH holds them): every object's vertices are placed in world space
/// (x = worldFromMesh · (anchor + position), double), and vertices at one position share an
/// id. Welding the vertices, not the corners, sorts a sixth as many positions.
std::vector<uint32_t> weldedTriangles(const Scene& scene) {
  const WorldObjects all = worldObjects(scene);
  if (all.vertices >= (size_t(1) << 31))
    throw Error(cat("checkClosed: ", all.vertices, " vertices is more than it handles"));
  std::vector<glm::dvec3> positions(all.vertices);
  for (const WorldObject& o : all.objects)
    parallelFor(o.mesh->vertexCount, 1 << 16, [&](size_t begin, size_t end) {
      const WorldObject placed = o;  // local: `positions` cannot alias it
      for (size_t v = begin; v < end; ++v) positions[placed.firstVertex + v] = placed.vertex(v);
    });
  const std::vector<uint32_t> ids = weldedIds(positions);
  std::vector<uint32_t> triangles(3 * all.triangles);
  for (const WorldObject& o : all.objects) {
    uint32_t* out = triangles.data() + 3 * o.firstTriangle;
    parallelFor(3 * o.triangles, 1 << 16, [&](size_t begin, size_t end) {
      for (size_t k = begin; k < end; ++k) out[k] = ids[o.firstVertex + o.indices[k]];
    });
  }
  return triangles;
}

/// An edge as (lower id << 32 | higher id) << 1 | (1 when traversed from the lower id).
uint64_t edgeKey(uint32_t from, uint32_t to) {
  const uint64_t lo = std::min(from, to), hi = std::max(from, to);
  return ((lo << 32 | hi) << 1) | uint64_t(from < to);
}

}  // namespace

ClosedCheck checkClosed(const Scene& scene) {
  const std::vector<uint32_t> ids = weldedTriangles(scene);
  const size_t triangles = ids.size() / 3;
  // Three keys per triangle; a degenerate triangle (two corners at one position) has none.
  std::vector<uint64_t> keys(3 * triangles, std::numeric_limits<uint64_t>::max());
  parallelFor(triangles, 1 << 14, [&](size_t begin, size_t end) {
    for (size_t t = begin; t < end; ++t) {
      const uint32_t a = ids[3 * t], b = ids[3 * t + 1], c = ids[3 * t + 2];
      if (a == b || b == c || c == a) continue;
      keys[3 * t] = edgeKey(a, b), keys[3 * t + 1] = edgeKey(b, c), keys[3 * t + 2] = edgeKey(c, a);
    }
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  ClosedCheck check;
  for (size_t k = 0; k < keys.size() && keys[k] != std::numeric_limits<uint64_t>::max();) {
    size_t end = k, forward = 0;
    for (; end < keys.size() && keys[end] >> 1 == keys[k] >> 1; ++end) forward += keys[end] & 1;
    const size_t uses = end - k;
    ++check.edges;
    if (uses == 1)
      ++check.boundaryEdges;
    else if (uses > 2)
      ++check.nonManifoldEdges;
    else if (forward != 1)
      ++check.misorientedEdges;
    k = end;
  }
  check.closed = check.edges > 0 && check.boundaryEdges == 0 && check.nonManifoldEdges == 0 &&
                 check.misorientedEdges == 0;
  return check;
}

// ---------------------------------------------------------------------------------------------
// Parity

namespace {

struct ParityDirections {
  glm::vec3 d[kParityDirectionCount];
  ParityDirections() {
    // Spherical Fibonacci points with irrational offsets, visited with a stride coprime to
    // the count so that consecutive directions are far apart.
    const double golden = 0.6180339887498949, pi = 3.14159265358979323846;
    for (int j = 0; j < kParityDirectionCount; ++j) {
      const int k = (j * 13) % kParityDirectionCount;
      const double z = 1.0 - 2.0 * (k + golden) / (kParityDirectionCount + 0.4142135623730951);
      const double phi = 2.0 * pi * (k * golden + 0.1415926535897932);
      const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
      d[j] = glm::normalize(glm::vec3(glm::dvec3(s * std::cos(phi), s * std::sin(phi), z)));
    }
  }
};

const ParityDirections& parityDirections() {
  static const ParityDirections directions;
  return directions;
}

/// A hit as parity judges it: Embree's raw ids (chunks resolved), Ng in the space Embree
/// reports it in (the mesh's for an instanced hit).
struct ParityHitView {
  float t;
  glm::vec3 ng;
  float u, v;
  unsigned geomID, instID, primID;
};

/// Whether a hit is one whose crossing cannot be counted with certainty: near an edge or a
/// vertex (where Embree's watertight test may report both triangles, or the second one a
/// float later), grazing, or at the ray's origin (a point on the surface).
bool ambiguousParityHit(const Scene& scene, float diagonal, float band, const ParityHitView& h,
                        const glm::vec3& dir) {
  const float t = h.t;
  if (t < band) return true;
  const bool instanced = h.instID != RTC_INVALID_GEOMETRY_ID;
  const unsigned object = instanced ? h.instID : h.geomID;
  glm::vec3 ng = h.ng;
  if (instanced) ng = scene.normalFromMesh(object) * ng;
  if (!(std::abs(glm::dot(ng, dir)) >= kParityGrazingCosine * glm::length(ng))) return true;
  // The hit point's distance to each edge: its barycentric weight times the triangle's
  // height over that edge (mesh units).
  const Mesh& mesh = scene.objectMesh(object);
  const size_t triangle = scene.meshTriangle(object, h.primID);
  const glm::vec3 v0 = mesh.vertex(mesh.indices[3 * triangle]),
                  v1 = mesh.vertex(mesh.indices[3 * triangle + 1]),
                  v2 = mesh.vertex(mesh.indices[3 * triangle + 2]);
  const float twiceArea = glm::length(glm::cross(v1 - v0, v2 - v0));
  const float u = h.u, v = h.v, w = 1.0f - u - v;
  const float margin = kParityEdgeTolerance * (t + diagonal);
  return !(w * twiceArea > margin * glm::length(v2 - v1) &&
           u * twiceArea > margin * glm::length(v0 - v2) &&
           v * twiceArea > margin * glm::length(v1 - v0));
}

/// A hit the parity filter recorded.
struct ParityHit {
  float t;
  bool ambiguous;
};

/// What the retrace finds along a ray whose every hit is known: it takes the hits in order
/// of t, counting each distinct t once (tnear moves to the next float past a hit, so hits at
/// the same t are one crossing), and stops at the first ambiguous one. Of hits at one t the
/// retrace sees the one Embree reports; the walk calls the crossing ambiguous when any is.
/// Hits at one t lie on a shared edge or vertex (ambiguous on both sides) or on coincident
/// triangles, which a closed surface has not.
struct ParityWalk {
  int crossings = 0;
  bool ambiguous = false;
};
ParityWalk walkParityHits(std::vector<ParityHit>& hits) {
  std::sort(hits.begin(), hits.end(),
            [](const ParityHit& a, const ParityHit& b) { return a.t < b.t; });
  ParityWalk walk;
  for (size_t i = 0; i < hits.size();) {
    size_t end = i;
    bool ambiguous = false;
    for (; end < hits.size() && hits[end].t == hits[i].t; ++end) ambiguous |= hits[end].ambiguous;
    if (ambiguous) {
      walk.ambiguous = true;
      return walk;
    }
    ++walk.crossings;
    i = end;
  }
  return walk;
}

/// Parity's collector (CollectingContext): each hit, with whether it is ambiguous, in its
/// lane's list.
struct ParityHitCollector {
  const Scene* scene = nullptr;
  float diagonal = 0, band = 0;
  std::vector<ParityHit>* lanes[16] = {};
  glm::vec3 dir[16];

  void operator()(const RTCFilterFunctionNArguments* args, unsigned i) const {
    const unsigned n = args->N;
    ParityHitView h{RTCRayN_tfar(args->ray, n, i),
                    glm::vec3(RTCHitN_Ng_x(args->hit, n, i), RTCHitN_Ng_y(args->hit, n, i),
                              RTCHitN_Ng_z(args->hit, n, i)),
                    RTCHitN_u(args->hit, n, i),
                    RTCHitN_v(args->hit, n, i),
                    RTCHitN_geomID(args->hit, n, i),
                    RTCHitN_instID(args->hit, n, i, 0),
                    RTCHitN_primID(args->hit, n, i)};
    if (scene->hasChunks()) scene->resolveChunkHits(&h.geomID, &h.primID, &h.instID, 1);
    const unsigned lane = RTCRayN_id(args->ray, n, i);
    lanes[lane]->push_back({h.t, ambiguousParityHit(*scene, diagonal, band, h, dir[lane])});
  }
};

/// Parity's packet width.
constexpr int kParityPacket = 8;

/// One point's parity rays in flight: its current direction and the crossings so far.
struct ParityLane {
  size_t point = 0;
  glm::vec3 org{0.0f};  ///< the point, render space
  int direction = 0;
  float tnear = 0;
  int crossings = 0;
  int votes = 0, insideVotes = 0;
  bool live = false;
};

/// Parity over the points order[begin, end): lanes of a packet of N rays, each lane taking
/// the next point when its point is decided.
template <int N>
class ParityStream {
 public:
  ParityStream(const Scene& scene, const double* points, const size_t* order,
               const InsideOptions& options, float diagonal, InsideResult& result)
      : scene_(scene),
        points_(points),
        order_(order),
        options_(options),
        diagonal_(diagonal),
        band_(kParitySurfaceBand * diagonal),
        result_(result) {}

  void run(size_t begin, size_t end) {
    next_ = begin, end_ = end;
    for (ParityLane& lane : lanes_) start(lane);
    const bool byFilter = scene_.options().contextFilter;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    alignas(64) typename PacketOf<N>::type packet;
    alignas(64) int valid[N];
    while (true) {
      int live = 0;
      for (int k = 0; k < N; ++k) {
        const ParityLane& lane = lanes_[k];
        const glm::vec3 dir = parityDirections().d[lane.direction];
        packet.ray.org_x[k] = lane.org.x, packet.ray.org_y[k] = lane.org.y;
        packet.ray.org_z[k] = lane.org.z, packet.ray.dir_x[k] = dir.x;
        packet.ray.dir_y[k] = dir.y, packet.ray.dir_z[k] = dir.z;
        packet.ray.tnear[k] = lane.tnear;
        packet.ray.tfar[k] = std::numeric_limits<float>::infinity();
        packet.ray.time[k] = 0, packet.ray.mask[k] = 0xFFFFFFFFu;
        packet.ray.id[k] = unsigned(k), packet.ray.flags[k] = 0;
        valid[k] = lane.live ? -1 : 0;
        live += lane.live;
      }
      if (live == 0) break;
      if (byFilter) {
        traceByFilter(packet, valid);
        continue;
      }
      clearHits<N>(packet);
      intersectScene<N>(scene_, &ctx, valid, packet);
      for (int k = 0; k < N; ++k) {
        ParityLane& lane = lanes_[k];
        if (!lane.live) continue;
        bool decided = false;
        if (!valid[k])  // a ray Embree cannot take (coordinates beyond its range)
          decided = decide(lane, false);
        else if (packet.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID)
          decided = endDirection(lane, true);
        else if (ambiguous(packet, k, parityDirections().d[lane.direction]))
          ++discarded_, decided = endDirection(lane, false);
        else
          ++lane.crossings, lane.tnear = std::nextafter(packet.ray.tfar[k], INFINITY);
        if (decided) start(lane);
      }
    }
  }

  size_t discarded() const { return discarded_; }
  size_t undecided() const { return undecided_; }

 private:
  const Scene& scene_;
  const double* points_;
  const size_t* order_;
  const InsideOptions& options_;
  float diagonal_, band_;
  InsideResult& result_;
  ParityLane lanes_[N];
  std::vector<ParityHit> hits_[N];  ///< traceByFilter's hits of each lane
  size_t next_ = 0, end_ = 0;
  size_t discarded_ = 0, undecided_ = 0;

  /// Gives the lane the next point, or leaves it dead. The stream holds only points inside
  /// the scene's box (ParityOrder::inBox).
  void start(ParityLane& lane) {
    lane = ParityLane{};
    if (next_ == end_) return;
    const size_t i = order_[next_++];
    const glm::dvec3 p(points_[3 * i], points_[3 * i + 1], points_[3 * i + 2]);
    lane.point = i;
    lane.org = glm::vec3(p - scene_.renderOrigin());
    lane.live = true;
  }

  /// Writes the lane's verdict; true.
  bool decide(ParityLane& lane, bool inside) {
    result_.inside[lane.point] = inside ? 1 : 0;
    return true;
  }

  /// Ends the lane's current direction, with its vote (`vote`) or discarded, and turns it to
  /// the next one. True when the point is decided:
  /// a majority of parityDirections votes on one side, or the directions used up (a majority
  /// of the votes there are; none: undecided, outside).
  bool endDirection(ParityLane& lane, bool vote) {
    if (vote) ++lane.votes, lane.insideVotes += lane.crossings & 1;
    // Decided once either side holds a majority of parityDirections.
    const int majority = options_.parityDirections / 2 + 1;
    if (lane.insideVotes >= majority || lane.votes - lane.insideVotes >= majority)
      return decide(lane, lane.insideVotes >= majority);
    if (++lane.direction == kParityDirectionCount) {
      if (lane.votes == 0) ++undecided_;
      return decide(lane, 2 * lane.insideVotes > lane.votes);
    }
    lane.crossings = 0, lane.tnear = 0;
    return false;
  }

  /// Whether lane k's hit is one whose crossing cannot be counted with certainty
  /// (ambiguousParityHit).
  bool ambiguous(const typename PacketOf<N>::type& p, int k, const glm::vec3& dir) const {
    const ParityHitView h{p.ray.tfar[k],   glm::vec3(p.hit.Ng_x[k], p.hit.Ng_y[k], p.hit.Ng_z[k]),
                          p.hit.u[k],      p.hit.v[k],
                          p.hit.geomID[k], p.hit.instID[0][k],
                          p.hit.primID[k]};
    return ambiguousParityHit(scene_, diagonal_, band_, h, dir);
  }

  /// One traversal per direction: the context filter records every hit of each lane (its t
  /// and whether it is ambiguous) and rejects it, so the ray goes on to the scene's end. The
  /// lane's hits, in order of t, then give what the retrace would have found.
  void traceByFilter(typename PacketOf<N>::type& packet, int* valid) {
    static_assert(N <= 16, "ParityHitCollector holds 16 lanes");
    CollectingContext<ParityHitCollector> ctx;
    ParityHitCollector& collector = ctx.collector;
    collector.scene = &scene_;
    collector.diagonal = diagonal_, collector.band = band_;
    for (int k = 0; k < N; ++k) {
      collector.lanes[k] = &hits_[k];
      collector.dir[k] = parityDirections().d[lanes_[k].direction];
      hits_[k].clear();
    }
    clearHits<N>(packet);
    intersectScene<N>(scene_, &ctx.base, valid, packet);
    for (int k = 0; k < N; ++k) {
      ParityLane& lane = lanes_[k];
      if (!lane.live) continue;
      bool decided = false;
      if (!valid[k]) {
        decided = decide(lane, false);
      } else {
        const ParityWalk walk = walkParityHits(hits_[k]);
        if (walk.ambiguous) {
          ++discarded_, decided = endDirection(lane, false);
        } else {
          lane.crossings = walk.crossings;
          decided = endDirection(lane, true);
        }
      }
      if (decided) start(lane);
    }
  }
};

float sceneDiagonal(const Scene& scene) {
  const std::optional<SceneBox>& box = scene.box();
  return box ? glm::length(box->hi - box->lo) : 0.0f;
}

void checkOptions(const InsideOptions& options) {
  checkParityDirections(options.parityDirections, "insideOf: parityDirections");
  if (!(options.windingBeta > 1.0) || !std::isfinite(options.windingBeta))
    throw Error(
        cat("insideOf: windingBeta ", options.windingBeta, " must be a finite number above 1"));
}

/// Cells per axis of parityOrder's grid over the scene's box (64³ cells, 18-bit Morton keys).
constexpr int kParityOrderBits = 6;

/// The order parity takes the points in: those inside the scene's box (the only ones that
/// trace rays) by cell of a 64³ grid over the box, cells in Morton order, so that a packet's
/// lanes hold neighbouring rays; then the others. Points outside the box (which holds every
/// triangle) are outside without a ray: no surface can enclose them, so rays start within a
/// box diagonal of the surface and Embree's rounding, which grows with the distance from the
/// ray's origin, stays at the scene's scale. A counting sort: linear, where a full Morton sort
/// of a million points took a tenth of parity's time. Each point's answer does not depend on
/// the order, only the speed does.
struct ParityOrder {
  std::vector<size_t> order;
  size_t inBox = 0;      ///< order[0, inBox) are inside the box
  size_t nonFinite = 0;  ///< points with a coordinate not finite (among the others)
};
ParityOrder parityOrder(const Scene& scene, const double* points, size_t count) {
  const std::optional<SceneBox>& box = scene.box();
  constexpr uint32_t cells = 1u << (3 * kParityOrderBits), outside = cells;
  std::vector<uint32_t> key(count, outside);
  if (box) {
    const glm::dvec3 lo(box->lo), hi(box->hi), origin = scene.renderOrigin();
    const glm::dvec3 scale = double(1 << kParityOrderBits) / glm::max(hi - lo, glm::dvec3(1e-300));
    parallelFor(count, 1 << 14, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        const glm::dvec3 org =
            glm::dvec3(points[3 * i], points[3 * i + 1], points[3 * i + 2]) - origin;
        if (!(glm::all(glm::greaterThanEqual(org, lo)) && glm::all(glm::lessThanEqual(org, hi))))
          continue;  // also NaN
        uint32_t k = 0;
        for (int a = 0; a < 3; ++a) {
          const double c =
              std::min((org[a] - lo[a]) * scale[a], double((1 << kParityOrderBits) - 1));
          k |= uint32_t(spreadBits(uint64_t(c))) << a;
        }
        key[i] = k;
      }
    });
  }
  std::vector<size_t> start(cells + 2, 0);
  for (uint32_t k : key) ++start[k + 1];
  for (size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  ParityOrder po;
  po.inBox = start[outside];
  po.order.resize(count);
  for (size_t i = 0; i < count; ++i) po.order[start[key[i]]++] = i;
  for (size_t n = po.inBox; n < count; ++n) {
    const double* p = points + 3 * po.order[n];
    po.nonFinite += !(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]));
  }
  return po;
}

void insideByParity(const Scene& scene, const double* points, size_t count,
                    const InsideOptions& options, InsideResult& result) {
  const float diagonal = sceneDiagonal(scene);
  // The points outside the box keep insideOf's 0.
  const ParityOrder po = parityOrder(scene, points, count);
  std::atomic<size_t> discarded{0}, undecided{0};
  parallelFor(po.inBox, 1024, [&](size_t begin, size_t end) {
    ParityStream<kParityPacket> stream(scene, points, po.order.data(), options, diagonal, result);
    stream.run(begin, end);
    discarded += stream.discarded();
    undecided += stream.undecided();
  });
  result.discardedRays = discarded;
  result.undecided = undecided;
  result.nonFinite = po.nonFinite;
}

void insideByWinding(const Scene& scene, const double* points, size_t count,
                     const InsideOptions& options, InsideResult& result) {
  std::optional<WindingNumberTree> built;
  if (!options.windingTree) built.emplace(worldTriangleCorners(scene));
  const WindingNumberTree& tree = options.windingTree ? *options.windingTree : *built;
  result.winding.resize(count);
  result.windingErrorBound.resize(count);
  tree.evaluate(points, count, options.windingBeta, result.winding.data(),
                result.windingErrorBound.data());
  size_t nonFinite = 0;
  for (size_t i = 0; i < count; ++i) {
    nonFinite += std::isnan(result.winding[i]);
    result.inside[i] = result.winding[i] > 0.5 ? 1 : 0;
  }
  result.nonFinite = nonFinite;
}

}  // namespace

void checkParityDirections(int directions, const char* name) {
  if (directions < 1 || directions % 2 == 0 || directions > kMaxParityDirections)
    throw Error(cat(name, " ", directions, " must be odd, in [1, ", kMaxParityDirections, "]"));
}

glm::vec3 parityDirection(int k) {
  if (k < 0 || k >= kParityDirectionCount)
    throw Error(cat("parityDirection: ", k, " is not in [0, ", kParityDirectionCount, ")"));
  return parityDirections().d[k];
}

InsideMethod resolvedInsideMethod(InsideMethod asked, bool closed) {
  if (asked != InsideMethod::Automatic) return asked;
  return closed ? InsideMethod::Parity : InsideMethod::Winding;
}

InsideResult insideOf(const Scene& scene, const double* points, size_t count,
                      const InsideOptions& options) {
  checkOptions(options);
  if (worldObjects(scene).triangles == 0) throw Error("insideOf: the scene has no triangles");
  InsideResult result;
  const bool automatic = options.method == InsideMethod::Automatic;
  const bool closed =
      automatic && (options.closed ? options.closed->closed : checkClosed(scene).closed);
  result.method = resolvedInsideMethod(options.method, closed);
  result.inside.assign(count, 0);
  if (result.method == InsideMethod::Parity)
    insideByParity(scene, points, count, options, result);
  else
    insideByWinding(scene, points, count, options, result);
  return result;
}

}  // namespace aperture
