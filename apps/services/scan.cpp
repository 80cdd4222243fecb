#include "apps/services/scan.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <type_traits>

#include "apps/services/render_options.h"
#include "core/engine/intersect_scene.h"
#include "core/engine/layers.h"
#include "core/mesh/ply.h"
#include "core/points/point_writers.h"
#include "core/queries/trace.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/spelling.h"

namespace aperture::app {

namespace {

namespace pf = point_fields;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Rays per chunk of the parallel loop (fixed: the work of a chunk does not depend on threads).
/// A multiple of the packet width, so that no packet straddles two chunks.
constexpr size_t kScanChunk = 4096;
constexpr int kScanPacket = 16;
static_assert(kScanChunk % kScanPacket == 0, "packets never straddle chunks");
/// Noise index of surface k of ray i: distinct for every (ray, surface) of a sweep.
uint64_t noiseIndex(size_t ray, int surface) { return uint64_t(ray) * 64u + uint64_t(surface); }

}  // namespace

/// What the fields pass reads of an object, gathered once per scanner.
struct ScanObjectFields {
  const uint32_t* reflectance;      ///< the face property, percent; null: 1
  const uint32_t* sourceTriangles;  ///< Mesh::sourceTriangles; null: the identity
  const uint32_t* faceGroups;       ///< Mesh::faceGroups; null: none
  ObjectIds ids;                    ///< Scene::objectIds
  const glm::mat3* normalFromMesh;  ///< Scene::normalFromMesh; null: the identity
};

/// One point-to-be as a chunk's trace leaves it, before the point's fields are derived from it
/// and written (32 bytes). Trivial: the buffers of them are left unwritten when they grow.
struct ScanSurface {
  double range;       ///< metres, reported (with the beam's range offset and noise)
  float incidence;    ///< |cos| between the ray and the surface's normal
  float intensity;    ///< SweepContext::intensityOf, computed once (it also picks the strongest)
  uint32_t object;    ///< the object hit
  uint32_t triangle;  ///< the stored triangle (Scene::meshTriangle), for the face properties
  uint32_t ray;       ///< its ray's index in the sweep
  uint8_t number;     ///< its return number along the ray, from 1 (ScanReturns::All)
  uint8_t returns;    ///< the ray's returns (ScanReturns::All)
};
static_assert(sizeof(ScanSurface) == 32, "the documented size");

namespace {

using Surface = ScanSurface;
static_assert(std::is_trivially_default_constructible<Surface>::value, "left unwritten");

struct SweepContext {
  const Scene& scene;
  const LidarSensor& sensor;
  const LidarRays& rays;
  const ScanOptions& options;
  const std::vector<ScanObjectFields>& objects;
  PoseMatrix sweepStartFromWorld;
  std::vector<PoseMatrix> sensorFromWorld;  ///< per pose of `rays`

  /// The documented intensity model: reflectance (the face property in percent, else 1) ·
  /// incidence / range².
  float intensityOf(const Surface& s) const {
    const uint32_t* r = objects[s.object].reflectance;
    const double rho = r ? double(r[s.triangle]) / 100.0 : 1.0;
    return float(rho * double(s.incidence) / (s.range * s.range));
  }
  uint32_t primIdOf(const Surface& s) const {
    const uint32_t* source = objects[s.object].sourceTriangles;
    return source ? source[s.triangle] : s.triangle;
  }
  /// The instance: the object's, plus the triangle's OBJ group.
  uint32_t instanceOf(const Surface& s) const {
    const ScanObjectFields& o = objects[s.object];
    return o.ids.instanceOfTriangle(o.faceGroups, s.triangle);
  }
  /// Where the ray of `s` met the surface, in world coordinates.
  glm::dvec3 worldPointOf(const Surface& s) const {
    const size_t i = s.ray;
    const double travel = s.range - double(rays.rangeOffset[i]);
    return rays.origin[i] + rays.direction[i] * travel;
  }
  /// Calls f(toFrame) with toFrame(s, world) giving the world point of `s` in the frame asked
  /// for: the frame is chosen once, outside the caller's loop over points.
  template <class F>
  void withFrame(const F& f) const {
    switch (options.frame) {
      case ScanFrame::Sensor:
        return f([this](const Surface& s, const glm::dvec3& world) {
          return sensorFromWorld[rays.poseIndex[s.ray]].apply(world);
        });
      case ScanFrame::World:
        return f([](const Surface&, const glm::dvec3& world) { return world; });
      case ScanFrame::SweepStart:
        return f([this](const Surface&, const glm::dvec3& world) {
          return sweepStartFromWorld.apply(world);
        });
    }
  }
};

/// Refuses a ray of [first, last) that fires before the sweep's start or past what the uint32
/// time field holds (chunk by chunk, inside the parallel loop, rather than in a serial pass
/// over the sweep's rays before it).
void checkFiringTimes(const SweepContext& c, size_t first, size_t last) {
  const int64_t* t = c.rays.timeNs.data();
  bool inRange = true;
  for (size_t i = first; i < last; ++i) inRange &= t[i] >= 0 && t[i] <= int64_t(UINT32_MAX);
  if (inRange) return;
  for (size_t i = first; i < last; ++i)
    if (t[i] < 0 || t[i] > int64_t(UINT32_MAX))
      throw Error(cat(c.sensor.source.path, ": ray ", i, " fires ", t[i],
                      " ns after the sweep's start, past the uint32 time field (4.29 s)"));
}

/// Surface k (0 nearest) along ray i, hit at `h`; false when noise drops it or its range falls
/// outside [minRange, maxRange].
bool surfaceOf(const SweepContext& c, size_t i, const LayerHit& h, int k, Surface& s) {
  double range = double(h.t) + double(c.rays.rangeOffset[i]);
  if (c.options.noise.enabled()) {
    const std::optional<double> noisy =
        applyRangeNoise(c.options.noise, range, c.rays.sweep, noiseIndex(i, k));
    if (!noisy) return false;
    range = *noisy;
  }
  if (range < c.sensor.minRange || range > c.sensor.maxRange || range <= 0) return false;
  const unsigned object = h.object();
  const glm::mat3* toWorld = c.objects[object].normalFromMesh;
  const glm::vec3 n = toWorld ? *toWorld * h.ng : h.ng;
  const float len = glm::length(n);
  s.range = range;
  s.incidence = len > 0 ? std::fabs(glm::dot(n, glm::vec3(c.rays.direction[i]))) / len : 0.0f;
  s.object = object;
  s.triangle = c.scene.meshTriangle(object, h.primID);
  s.ray = uint32_t(i);
  s.number = 1;
  s.returns = 1;
  s.intensity = c.intensityOf(s);
  return true;
}

/// The closest hits of rays [first, last), in packets: emit(q, surface) for the q-th point, in
/// ray order. Returns how many.
template <class Emit>
size_t traceFirstReturns(const SweepContext& c, size_t first, size_t last, const Emit& emit) {
  PacketBuffers<kScanPacket> pb;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  const glm::dvec3& renderOrigin = c.scene.renderOrigin();
  const HitLanes& h = pb.hits;
  size_t count = 0;
  for (size_t p = first; p < last; p += kScanPacket) {
    fillLidarLanes(c.rays, p, renderOrigin, pb.lanes, pb.valid);
    clearHits<kScanPacket>(pb.packet);
    intersectScene<kScanPacket>(c.scene, &ctx, pb.valid, pb.packet, /*activeTraceable=*/true);
    const int lanes = int(std::min(size_t(kScanPacket), last - p));
    for (int k = 0; k < lanes; ++k) {
      if (!pb.valid[k] || h.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
      const LayerHit hit{h.tfar[k], glm::vec3(h.ngX[k], h.ngY[k], h.ngZ[k]), h.primID[k],
                         h.geomID[k], h.instID[k]};
      Surface s;
      if (surfaceOf(c, p + size_t(k), hit, 0, s)) emit(count++, s);
    }
  }
  return count;
}

/// The returns of rays [first, last) from the surfaces the layers' search finds
/// (core/engine/layers.h): every kept one (ScanReturns::All, numbered), else the last or the
/// strongest kept: emit(q, surface) for the q-th point, in ray order. Returns how many.
template <class Emit>
size_t traceReturns(const SweepContext& c, size_t first, size_t last, const Emit& emit) {
  const ScanOptions& o = c.options;
  const SurfaceSearch search{o.maxSurfaces, float(o.returnSeparation), defaultLayerMethod()};
  PacketBuffers<kScanPacket> pb;
  std::vector<LaneLayers> found(kScanPacket);
  std::vector<Surface> kept(size_t(o.maxSurfaces));
  const glm::dvec3& renderOrigin = c.scene.renderOrigin();
  size_t count = 0;
  for (size_t p = first; p < last; p += kScanPacket) {
    fillLidarLanes(c.rays, p, renderOrigin, pb.lanes, pb.valid);
    traceSurfaces<kScanPacket>(c.scene, search, pb, nullptr, found.data());
    const int lanes = int(std::min(size_t(kScanPacket), last - p));
    for (int k = 0; k < lanes; ++k) {
      const size_t i = p + size_t(k);
      size_t n = 0, chosen = 0;
      float best = -1.0f;
      for (int j = 0; j < found[size_t(k)].count; ++j) {
        Surface& s = kept[n];
        if (!surfaceOf(c, i, found[size_t(k)].hit[j], j, s)) continue;
        if (o.returns == ScanReturns::Strongest) {
          if (s.intensity > best) best = s.intensity, chosen = n;
        } else {
          chosen = n;  // last: the farthest kept
        }
        s.number = uint8_t(n + 1);
        ++n;
      }
      if (n == 0) continue;
      if (o.returns != ScanReturns::All) {
        emit(count++, kept[chosen]);
        continue;
      }
      for (size_t q = 0; q < n; ++q) {
        kept[q].returns = uint8_t(n);
        emit(count++, kept[q]);
      }
    }
  }
  return count;
}

/// Adds a sweep's fields to its cloud (left unwritten), the k-th in the k-th buffer of a
/// recycled sweep when there is one (SweepScanner::recycle).
class FieldAdder {
 public:
  FieldAdder(PointCloud& cloud, std::vector<LargeBuffer<unsigned char>>& spare)
      : cloud_(cloud), spare_(spare) {}
  ~FieldAdder() { spare_.clear(); }
  FieldAdder(const FieldAdder&) = delete;
  FieldAdder& operator=(const FieldAdder&) = delete;
  PointField& add(const std::string& name, PointType type) {
    if (next_ < spare_.size()) return cloud_.addField(name, type, std::move(spare_[next_++]));
    return cloud_.addField(name, type, false);
  }
  template <typename T>
  T* add(const std::string& name, PointType type) {
    return add(name, type).as<T>();
  }

 private:
  PointCloud& cloud_;
  std::vector<LargeBuffer<unsigned char>>& spare_;
  size_t next_ = 0;
};

PointType positionType(ScanFrame frame) {
  return frame == ScanFrame::World ? PointType::Float64 : PointType::Float32;
}

/// The cloud's fields as a sweep writes them (pointers into its PointFields).
struct PointSink {
  float* xyzFloat[3] = {};    ///< x, y, z as float (frames sensor, sweep-start), or null
  double* xyzDouble[3] = {};  ///< x, y, z as double (frame world), or null
  float *range = nullptr, *azimuth = nullptr, *incidence = nullptr, *intensity = nullptr;
  uint32_t *time = nullptr, *column = nullptr, *primid = nullptr, *geomid = nullptr,
           *instance = nullptr;
  uint16_t* ring = nullptr;
  uint8_t *returnNumber = nullptr, *returns = nullptr;  ///< null unless ScanReturns::All
  std::vector<uint32_t*> properties;                    ///< per face property, null when left out
  const std::vector<const MeshProperty*>* propertyOf;   ///< object-major: [object · P + p]
};

/// Adds the fields of a sweep that `selected` selects to `cloud` (cloud.size values each, left
/// unwritten; in the buffers of a recycled sweep, `spare`, when there are some) and returns
/// them (null for those left out).
PointSink addPointFields(PointCloud& cloud, const ScanOptions& options,
                         const PointFieldSelection& selected,
                         std::vector<LargeBuffer<unsigned char>>& spare,
                         const std::vector<const MeshProperty*>& propertyOf) {
  PointSink sink;
  FieldAdder fields(cloud, spare);
  auto add = [&](auto*& to, const char* name, PointType type) {
    using T = std::remove_reference_t<decltype(*to)>;
    to = selected.selects(name) ? fields.add<T>(name, type) : nullptr;
  };
  const PointType xyzType = positionType(options.frame);
  const char* xyz[3] = {pf::kX, pf::kY, pf::kZ};
  for (int a = 0; a < 3; ++a) {
    if (xyzType == PointType::Float64)
      add(sink.xyzDouble[a], xyz[a], xyzType);
    else
      add(sink.xyzFloat[a], xyz[a], xyzType);
  }
  add(sink.range, pf::kRange, PointType::Float32);
  add(sink.time, pf::kTime, PointType::UInt32);
  add(sink.ring, pf::kRing, PointType::UInt16);
  add(sink.column, pf::kColumn, PointType::UInt32);
  add(sink.azimuth, pf::kAzimuth, PointType::Float32);
  add(sink.incidence, pf::kIncidence, PointType::Float32);
  add(sink.intensity, pf::kIntensity, PointType::Float32);
  add(sink.primid, pf::kPrimId, PointType::UInt32);
  add(sink.geomid, pf::kGeomId, PointType::UInt32);
  add(sink.instance, pf::kInstance, PointType::UInt32);
  if (options.returns == ScanReturns::All) {
    add(sink.returnNumber, pf::kReturnNumber, PointType::UInt8);
    add(sink.returns, pf::kReturns, PointType::UInt8);
  }
  for (const std::string& name : options.faceProperties) {
    if (isStandardPointField(name))
      throw Error(cat("face property '", name, "' has the name of a standard point field"));
    uint32_t* p = nullptr;
    add(p, name.c_str(), PointType::UInt32);
    sink.properties.push_back(p);
  }
  sink.propertyOf = &propertyOf;
  // Adding a field may move the PointFields (not their values): the pointers above stay.
  return sink;
}

/// The positions of points [at, at + count) of the cloud, those of `xyz` not null: surfaces `s`
/// in the frame `toFrame` takes them to (SweepContext::withFrame).
template <class ToFrame, typename T>
void writePositions(const SweepContext& c, const ToFrame& toFrame, T* const (&xyz)[3], size_t at,
                    const Surface* s, size_t count) {
  if (xyz[0] && xyz[1] && xyz[2]) {
    T* __restrict x = xyz[0] + at;
    T* __restrict y = xyz[1] + at;
    T* __restrict z = xyz[2] + at;
    for (size_t q = 0; q < count; ++q) {
      const glm::dvec3 p = toFrame(s[q], c.worldPointOf(s[q]));
      x[q] = T(p.x), y[q] = T(p.y), z[q] = T(p.z);
    }
    return;
  }
  if (!xyz[0] && !xyz[1] && !xyz[2]) return;
  for (size_t q = 0; q < count; ++q) {
    const glm::dvec3 p = toFrame(s[q], c.worldPointOf(s[q]));
    for (int a = 0; a < 3; ++a)
      if (xyz[a]) xyz[a][at + q] = T(p[a]);
  }
}

/// Points [at, at + count) of the cloud: surfaces `s` with the fields of `f` (those not null),
/// a few fields at a time (short loops the compiler vectorises, over surfaces still in cache):
/// each group in one loop when every field of it is there, else field by field.
void writePoints(const SweepContext& c, const PointSink& f, size_t at, const Surface* s,
                 size_t count) {
  const LidarRays& rays = c.rays;
  c.withFrame([&](const auto& toFrame) {
    writePositions(c, toFrame, f.xyzFloat, at, s, count);
    writePositions(c, toFrame, f.xyzDouble, at, s, count);
  });
  float* __restrict range = f.range ? f.range + at : nullptr;
  float* __restrict incidence = f.incidence ? f.incidence + at : nullptr;
  uint32_t* __restrict geomid = f.geomid ? f.geomid + at : nullptr;
  if (range && incidence && geomid) {
    for (size_t q = 0; q < count; ++q) {
      range[q] = float(s[q].range);
      incidence[q] = s[q].incidence;
      geomid[q] = s[q].object;
    }
  } else {
    if (range)
      for (size_t q = 0; q < count; ++q) range[q] = float(s[q].range);
    if (incidence)
      for (size_t q = 0; q < count; ++q) incidence[q] = s[q].incidence;
    if (geomid)
      for (size_t q = 0; q < count; ++q) geomid[q] = s[q].object;
  }
  float* __restrict intensity = f.intensity ? f.intensity + at : nullptr;
  uint32_t* __restrict primid = f.primid ? f.primid + at : nullptr;
  uint32_t* __restrict instance = f.instance ? f.instance + at : nullptr;
  if (intensity && primid && instance) {
    for (size_t q = 0; q < count; ++q) {
      intensity[q] = s[q].intensity;
      primid[q] = c.primIdOf(s[q]);
      instance[q] = c.instanceOf(s[q]);
    }
  } else {
    if (intensity)
      for (size_t q = 0; q < count; ++q) intensity[q] = s[q].intensity;
    if (primid)
      for (size_t q = 0; q < count; ++q) primid[q] = c.primIdOf(s[q]);
    if (instance)
      for (size_t q = 0; q < count; ++q) instance[q] = c.instanceOf(s[q]);
  }
  uint32_t* __restrict time = f.time ? f.time + at : nullptr;
  uint16_t* __restrict ring = f.ring ? f.ring + at : nullptr;
  uint32_t* __restrict column = f.column ? f.column + at : nullptr;
  float* __restrict azimuth = f.azimuth ? f.azimuth + at : nullptr;
  auto azimuthOf = [&](size_t i) { return float(double(rays.azimuthDeg[i]) * M_PI / 180.0); };
  if (time && ring && column && azimuth) {
    for (size_t q = 0; q < count; ++q) {
      const size_t i = s[q].ray;
      time[q] = uint32_t(rays.timeNs[i]);
      ring[q] = uint16_t(rays.ring[i]);
      column[q] = rays.column[i];
      azimuth[q] = azimuthOf(i);
    }
  } else {
    if (time)
      for (size_t q = 0; q < count; ++q) time[q] = uint32_t(rays.timeNs[s[q].ray]);
    if (ring)
      for (size_t q = 0; q < count; ++q) ring[q] = uint16_t(rays.ring[s[q].ray]);
    if (column)
      for (size_t q = 0; q < count; ++q) column[q] = rays.column[s[q].ray];
    if (azimuth)
      for (size_t q = 0; q < count; ++q) azimuth[q] = azimuthOf(s[q].ray);
  }
  if (f.returnNumber)
    for (size_t q = 0; q < count; ++q) f.returnNumber[at + q] = s[q].number;
  if (f.returns)
    for (size_t q = 0; q < count; ++q) f.returns[at + q] = s[q].returns;
  const size_t P = f.properties.size();
  for (size_t p = 0; p < P; ++p)
    if (uint32_t* out = f.properties[p])
      for (size_t q = 0; q < count; ++q) {
        const MeshProperty* m = (*f.propertyOf)[s[q].object * P + p];
        out[at + q] = m ? m->values[s[q].triangle] : TraceHit::kNoHit;
      }
}

/// The range image of a sweep from its cloud: each point at its (ring, column) pixel
/// (pattern sensors: row 0, column the ray's index), misses 0 (ids 0xFFFFFFFF); `time` at
/// every ray's pixel.
RangeImage rangeImageOf(const LidarSensor& sensor, const LidarRays& rays, const PointCloud& cloud,
                        const std::vector<std::string>& faceProperties) {
  RangeImage img;
  img.rows = std::max(1, rays.rows);
  img.columns = std::max(1, rays.columns);
  img.pixelShiftByRow = sensor.pixelShiftByRow;
  const bool spinning = sensor.kind == LidarKind::Spinning;
  const size_t pixels = size_t(img.rows) * size_t(img.columns);
  auto pixelOf = [&](size_t ring, size_t column) -> std::optional<size_t> {
    const size_t row = spinning ? ring : 0;
    if (row >= size_t(img.rows) || column >= size_t(img.columns)) return std::nullopt;
    return row * size_t(img.columns) + column;
  };
  const uint16_t* ring = cloud.find(pf::kRing)->as<uint16_t>();
  const uint32_t* column = cloud.find(pf::kColumn)->as<uint32_t>();
  std::vector<size_t> at(cloud.size, pixels);  // each point's pixel, `pixels` for none
  for (size_t q = 0; q < cloud.size; ++q)
    if (const std::optional<size_t> px = pixelOf(ring[q], column[q])) at[q] = *px;
  // A channel from a field of the cloud: its value at the point's pixel, `miss` elsewhere.
  auto copy = [&](const std::string& name, PointType type, auto miss) {
    using T = decltype(miss);
    T* out = img.addChannel(name, type).template as<T>();
    std::fill(out, out + pixels, miss);
    const PointField& f = *cloud.find(name);
    for (size_t q = 0; q < cloud.size; ++q)
      if (at[q] < pixels) out[at[q]] = T(f.value(q));
  };
  auto* RANGE = img.addChannel("RANGE", PointType::UInt32).as<uint32_t>();
  const float* range = cloud.find(pf::kRange)->as<float>();
  for (size_t q = 0; q < cloud.size; ++q)
    if (at[q] < pixels) RANGE[at[q]] = uint32_t(std::lround(double(range[q]) * 1000.0));
  copy(pf::kRange, PointType::Float32, 0.0f);
  copy(pf::kIntensity, PointType::Float32, 0.0f);
  copy(pf::kIncidence, PointType::Float32, 0.0f);
  auto* time = img.addChannel(pf::kTime, PointType::UInt32).as<uint32_t>();
  for (size_t i = 0; i < rays.size(); ++i)
    if (const std::optional<size_t> px = pixelOf(rays.ring[i], spinning ? rays.column[i] : i))
      time[*px] = uint32_t(rays.timeNs[i]);
  for (const char* xyz : {pf::kX, pf::kY, pf::kZ}) copy(xyz, PointType::Float32, 0.0f);
  for (const char* id : {pf::kPrimId, pf::kGeomId, pf::kInstance})
    copy(id, PointType::UInt32, TraceHit::kNoHit);
  for (const std::string& name : faceProperties) copy(name, PointType::UInt32, TraceHit::kNoHit);
  return img;
}

}  // namespace

ScanFrame parseScanFrame(const std::string& name) {
  if (name == "sensor") return ScanFrame::Sensor;
  if (name == "world") return ScanFrame::World;
  if (name == "sweep-start") return ScanFrame::SweepStart;
  throw Error(cat("unknown frame '", name, "' (known: sensor, world, sweep-start)",
                  didYouMean(name, {"sensor", "world", "sweep-start"})));
}

const char* scanFrameName(ScanFrame frame) {
  switch (frame) {
    case ScanFrame::Sensor:
      return "sensor";
    case ScanFrame::World:
      return "world";
    case ScanFrame::SweepStart:
      return "sweep-start";
  }
  return "sensor";
}

ScanReturns parseScanReturns(const std::string& name) {
  if (name == "first") return ScanReturns::First;
  if (name == "last") return ScanReturns::Last;
  if (name == "strongest") return ScanReturns::Strongest;
  if (name == "all") return ScanReturns::All;
  throw Error(cat("unknown returns '", name, "' (known: first, last, strongest, all)",
                  didYouMean(name, {"first", "last", "strongest", "all"})));
}

const char* scanReturnsName(ScanReturns returns) {
  switch (returns) {
    case ScanReturns::First:
      return "first";
    case ScanReturns::Last:
      return "last";
    case ScanReturns::Strongest:
      return "strongest";
    case ScanReturns::All:
      return "all";
  }
  return "first";
}

void checkSurfacesPerRay(int surfaces, const char* what) {
  if (surfaces < 1 || surfaces > 64) throw Error(cat(what, " ", surfaces, " is outside 1..64"));
}

struct SweepScanner::State {
  std::vector<ScanObjectFields> objects;
  std::vector<const MeshProperty*> properties;  ///< object-major: [object · P + p]
  /// The sweep's points-to-be: chunk k's from k·kScanChunk·perRay on. Kept from one sweep to
  /// the next, so that only the first sweep's trace pays for mapping it.
  LargeBuffer<Surface> surfaces;
  std::vector<size_t> offset;
  /// The field buffers of a recycled sweep, in the order scan adds its fields.
  std::vector<LargeBuffer<unsigned char>> spare;
};

void SweepScanner::recycle(ScanSweep&& done) {
  state_->spare.clear();
  for (PointField& f : done.cloud.fields) state_->spare.push_back(std::move(f.bytes));
}

SweepScanner::SweepScanner(const Scene& scene, const LidarSensor& sensor,
                           const ScanOptions& options)
    : scene_(scene), sensor_(sensor), options_(options), state_(std::make_unique<State>()) {
  checkSurfacesPerRay(options.maxSurfaces, "surfaces per ray");
  for (size_t o = 0; o < scene.objectCount(); ++o) {
    const Mesh& mesh = scene.objectMesh(unsigned(o));
    const MeshProperty* r = mesh.property(PropertyDomain::Face, kReflectanceProperty);
    state_->objects.push_back({r ? r->values.data() : nullptr,
                               mesh.sourceTriangles.empty() ? nullptr : mesh.sourceTriangles.data(),
                               mesh.faceGroups.empty() ? nullptr : mesh.faceGroups.data(),
                               scene.objectIds(unsigned(o)),
                               scene.normalFromMesh(unsigned(o)) == glm::mat3(1.0f)
                                   ? nullptr
                                   : &scene.normalFromMesh(unsigned(o))});
    for (const std::string& name : options.faceProperties)
      state_->properties.push_back(mesh.property(PropertyDomain::Face, name));
  }
}

SweepScanner::~SweepScanner() = default;

ScanSweep SweepScanner::scan(const LidarRays& rays, bool rangeImage) {
  const Scene& scene = scene_;
  const LidarSensor& sensor = sensor_;
  const ScanOptions& options = options_;
  if (rangeImage && options.returns == ScanReturns::All)
    throw Error("a range image holds one return per ray: --returns all needs a point cloud");
  const auto t0 = Clock::now();
  SweepContext c{
      scene, sensor, rays, options, state_->objects, PoseMatrix(rays.sweepStartPose.inverse()), {}};
  for (const Pose& p : rays.poses) c.sensorFromWorld.emplace_back(p.inverse());
  const size_t n = rays.size();
  const bool all = options.returns == ScanReturns::All;

  // The cloud's fields, left unwritten: every value is written below. One return per ray
  // (first, last, strongest): sized for every ray, each chunk writes its points straight into
  // them from its first ray's row on, and they move down to their place afterwards. All
  // returns: a chunk's surfaces wait in the scanner's buffer until the counts place them.
  ScanSweep result;
  result.rays = n;
  PointCloud& cloud = result.cloud;
  cloud.size = n;
  cloud.startSeconds = double(rays.sweepStartNs) * 1e-9;
  // The fields asked for, and those a range image is made from.
  PointFieldSelection selected = options.fields;
  if (rangeImage) selected.add(pointFieldsWrittenAs(PointFormat::Npz, {}));
  PointSink sink;
  if (!all) sink = addPointFields(cloud, options, selected, state_->spare, state_->properties);

  // Trace in fixed chunks, counting each chunk's points (the cloud is the same on any thread
  // count).
  const size_t chunks = (n + kScanChunk - 1) / kScanChunk;
  std::vector<size_t>& offset = state_->offset;
  offset.assign(chunks + 1, 0);
  const size_t perRay = all ? size_t(options.maxSurfaces) : 1;
  LargeBuffer<Surface>& surfaces = state_->surfaces;
  if (all && surfaces.size() < n * perRay) resizeOnHugePages(surfaces, n * perRay);
  parallelForChunks(n, kScanChunk, [&](size_t chunk, size_t first, size_t last) {
    checkFiringTimes(c, first, last);
    if (all) {
      Surface* out = surfaces.data() + first * perRay;
      offset[chunk + 1] =
          traceReturns(c, first, last, [&](size_t q, const Surface& s) { out[q] = s; });
      return;
    }
    // The chunk is traced first, its surfaces kept in a buffer of the thread's (a chunk's
    // worth, reused: it stays in cache), then its points written field by field.
    thread_local std::vector<Surface> chunkSurfaces;
    chunkSurfaces.resize(kScanChunk);
    auto keep = [&](size_t q, const Surface& s) { chunkSurfaces[q] = s; };
    const size_t count = options.returns == ScanReturns::First
                             ? traceFirstReturns(c, first, last, keep)
                             : traceReturns(c, first, last, keep);
    writePoints(c, sink, first, chunkSurfaces.data(), count);
    offset[chunk + 1] = count;
  });
  std::vector<size_t> counts(offset.begin() + 1, offset.end());
  for (size_t k = 0; k < chunks; ++k) offset[k + 1] += offset[k];
  const size_t points = offset[chunks];

  if (all) {
    cloud.size = points;
    sink = addPointFields(cloud, options, selected, state_->spare, state_->properties);
    parallelForChunks(n, kScanChunk, [&](size_t chunk, size_t first, size_t) {
      const Surface* in = surfaces.data() + first * perRay;
      writePoints(c, sink, offset[chunk], in, counts[chunk]);
    });
  } else {
    // Chunk k's points move from row k·kScanChunk down to their offset, in chunk order (a
    // block's new rows only overlap rows already moved); none move when every ray hit.
    for (PointField& f : cloud.fields) {
      const size_t bytes = pointTypeSize(f.type);
      for (size_t k = 0; k < chunks; ++k)
        if (offset[k] != k * kScanChunk)
          std::memmove(f.bytes.data() + offset[k] * bytes, f.bytes.data() + k * kScanChunk * bytes,
                       counts[k] * bytes);
      f.bytes.resize(points * bytes);
    }
    cloud.size = points;
  }
  result.points = points;
  if (rangeImage) result.image = rangeImageOf(sensor, rays, cloud, options.faceProperties);
  result.traceSeconds = secondsSince(t0);
  return result;
}

ScanSweep scanSweep(const Scene& scene, const LidarSensor& sensor, const LidarRays& rays,
                    const ScanOptions& options, bool rangeImage) {
  return SweepScanner(scene, sensor, options).scan(rays, rangeImage);
}

namespace {

/// Whether every mesh of `spec` is a PLY file whose face element has the property `name` (so
/// the loader, which refuses a property a file lacks, may be asked for it).
bool everyMeshHasFaceProperty(const SceneSpec& spec, const std::string& name) {
  if (spec.meshes.empty()) return false;
  for (const MeshPlacement& m : spec.meshes) {
    if (toLowerAscii(std::filesystem::path(m.spec).extension().string()) != ".ply") return false;
    std::ifstream in(m.spec, std::ios::binary);
    std::string prefix(size_t(1) << 20, '\0');
    in.read(prefix.data(), std::streamsize(prefix.size()));
    prefix.resize(size_t(in.gcount()));
    const PlyHeader header = readPlyHeader(m.spec, prefix.data(), prefix.size());
    bool found = false;
    for (const PlyElement& e : header.elements)
      if (e.name == "face")
        for (const PlyProperty& p : e.props) found = found || (p.name == name && !p.list);
    if (!found) return false;
  }
  return true;
}

}  // namespace

SceneSpec scanSceneSpec(const SceneOptions& scene, const ScanOptions& options) {
  return withScanNeeds(scene.spec(), options);
}

SceneSpec withScanNeeds(SceneSpec spec, const ScanOptions& options) {
  auto want = [&](const std::string& name) {
    const PropertyAov p{PropertyDomain::Face, name};
    if (std::find(spec.properties.begin(), spec.properties.end(), p) == spec.properties.end())
      spec.properties.push_back(p);
  };
  if (everyMeshHasFaceProperty(spec, kReflectanceProperty)) want(kReflectanceProperty);
  for (const std::string& name : options.faceProperties) want(name);
  spec.build.contextFilter = spec.build.contextFilter || scanNeedsContextFilter(options);
  return spec;
}

bool scanNeedsContextFilter(const ScanOptions& options) {
  return options.returns != ScanReturns::First && defaultLayerMethod() == LayerMethod::Filter;
}

std::string expandSweepPattern(const std::string& pattern, int sweep) {
  std::string out;
  for (size_t k = 0; k < pattern.size(); ++k) {
    if (pattern[k] != '{') {
      out.push_back(pattern[k]);
      continue;
    }
    const size_t close = pattern.find('}', k);
    if (close == std::string::npos)
      throw Error(cat("'", pattern, "': a '{' without '}' (known: {sweep}, {sweep:0Nd})"));
    const std::string field = pattern.substr(k + 1, close - k - 1);
    if (field == "sweep") {
      out += std::to_string(sweep);
    } else if (field.size() >= 9 && field.compare(0, 7, "sweep:0") == 0 && field.back() == 'd') {
      const std::string digits = field.substr(7, field.size() - 8);
      const bool number = !digits.empty() && digits.size() <= 2 &&
                          std::all_of(digits.begin(), digits.end(), ::isdigit);
      const int width = number ? std::stoi(digits) : 0;
      if (width < 1 || width > 20)
        throw Error(
            cat("'", pattern, "': '{", field, "}' needs a width in 1..20, e.g. {sweep:06d}"));
      const std::string s = std::to_string(sweep);
      out += std::string(s.size() < size_t(width) ? size_t(width) - s.size() : 0, '0') + s;
    } else {
      throw Error(
          cat("'", pattern, "': unknown field '{", field, "}' (known: {sweep}, {sweep:0Nd})"));
    }
    k = close;
  }
  return out;
}

namespace {

/// Bare Embree on the same rays: rtcIntersect16 over packets of the sweep's rays, on the same
/// parallel loop and chunks, nothing else (no fields, no chunk or prim remapping).
double bareEmbreeSeconds(const Scene& scene, const std::vector<TraceRay>& rays, size_t* hits) {
  std::atomic<size_t> count{0};
  const auto t0 = Clock::now();
  parallelForChunks(rays.size(), kScanChunk, [&](size_t, size_t first, size_t last) {
    size_t local = 0;
    RTCIntersectContext ctx;
    for (size_t p = first; p < last; p += 16) {
      alignas(64) RTCRayHit16 rh;
      alignas(64) int valid[16];
      for (int k = 0; k < 16; ++k) {
        const size_t i = std::min(p + size_t(k), last - 1);
        valid[k] = p + size_t(k) < last ? -1 : 0;
        const TraceRay& r = rays[i];
        rh.ray.org_x[k] = r.org.x, rh.ray.org_y[k] = r.org.y, rh.ray.org_z[k] = r.org.z;
        rh.ray.dir_x[k] = r.dir.x, rh.ray.dir_y[k] = r.dir.y, rh.ray.dir_z[k] = r.dir.z;
        rh.ray.tnear[k] = r.tnear, rh.ray.tfar[k] = r.tfar;
        rh.ray.time[k] = 0, rh.ray.mask[k] = 0xFFFFFFFFu, rh.ray.id[k] = unsigned(k),
        rh.ray.flags[k] = 0;
        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcInitIntersectContext(&ctx);
      rtcIntersect16(valid, scene.handle(), &ctx, &rh);
      for (int k = 0; k < 16; ++k)
        if (valid[k] && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) ++local;
    }
    count += local;
  });
  if (hits) *hits = count;
  return secondsSince(t0);
}

/// CPU seconds of every thread of the process so far (user and system).
double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + double(t.tv_nsec) * 1e-9;
}

LidarSensor sensorOf(const ScanRequest& r) {
  LidarSensor sensor = loadLidar(r.lidar);
  if (r.columns > 0) {
    if (sensor.kind != LidarKind::Spinning)
      throw Error(
          cat("--columns: ", sensor.source.path, " is a pattern sensor, not a spinning one"));
    for (int& s : sensor.pixelShiftByRow)
      s = int(std::lround(double(s) * r.columns / sensor.columns));
    sensor.columns = r.columns;
    sensor.columnTimeNs = 0;
    sensor.columnWindow = {0, -1};
  }
  return sensor;
}

}  // namespace

PreparedScan prepareScan(const ScanRequest& r) {
  if (r.sweeps < 1) throw Error(cat("--sweeps ", r.sweeps, " must be at least 1"));
  if (r.out.empty()) throw Error("--out is required");
  const PointFormat format = pointFormatOf(r.out);
  const bool image = isRangeImageFormat(format);
  if (image && r.options.returns == ScanReturns::All)
    throw Error(cat("'", r.out,
                    "': a range image holds one return per ray; --returns all needs "
                    ".ply, .pcd, .las or .bin"));
  checkSurfacesPerRay(r.options.maxSurfaces, "--surfaces");
  if (r.sweeps > 1 && expandSweepPattern(r.out, 0) == expandSweepPattern(r.out, 1))
    throw Error(cat("--out '", r.out, "': ", r.sweeps, " sweeps need {sweep} in the path"));
  applyRangeNoise(r.options.noise, 1.0, 0, 0);  // checks σ and the dropout
  if (!(r.options.returnSeparation >= 0))
    throw Error(cat("--return-separation ", r.options.returnSeparation, " must be >= 0"));
  if (!r.labelField.empty() &&
      std::find(r.options.faceProperties.begin(), r.options.faceProperties.end(), r.labelField) ==
          r.options.faceProperties.end())
    throw Error(cat("--label '", r.labelField, "' must be one of the --property names"));
  const LidarSensor sensor = sensorOf(r);
  const Trajectory trajectory =
      r.trajectory.empty() ? Trajectory() : loadTrajectory(r.trajectory, r.trajectoryTimes);
  const int64_t period = sensor.periodNs();
  std::vector<std::string> paths;
  for (int k = 0; k < r.sweeps; ++k) {
    const int64_t start =
        sweepStartNs(r.startNs, k, period).value_or(trajectory.startNs() + int64_t(k) * period);
    for (int64_t t : {start, start + period - 1})
      if (!trajectory.covers(t))
        throw Error(cat("sweep ", k, " fires at ", formatTimeNs(t), " s, outside the trajectory '",
                        trajectory.source(), "' (", formatTimeNs(trajectory.startNs()), " to ",
                        formatTimeNs(trajectory.endNs()), " s)"));
    const std::string path = expandSweepPattern(r.out, k);
    const std::filesystem::path dir = std::filesystem::path(path).parent_path();
    if (!dir.empty() && !std::filesystem::is_directory(dir))
      throw Error(cat("--out '", path, "': the directory '", dir.string(), "' does not exist"));
    paths.push_back(path);
  }
  return {sensor, trajectory, paths, image};
}

void writeScans(const Scene& scene, const ScanRequest& r, const PreparedScan& prepared,
                const std::string& isa, int threads) {
  const LidarSensor& sensor = prepared.sensor;
  const Trajectory& trajectory = prepared.trajectory;
  const std::vector<std::string>& paths = prepared.paths;
  const bool image = prepared.image;
  const int64_t period = sensor.periodNs();
  PointWriteOptions writeOptions{
      r.labelField,
      {cat("aperture scan: ", sensor.name, ", frame ", scanFrameName(r.options.frame), ", returns ",
           scanReturnsName(r.options.returns))}};
  // Only the fields the output's format writes are computed.
  ScanOptions options = r.options;
  options.fields = pointFieldsWrittenAs(pointFormatOf(r.out), writeOptions);
  SweepScanner scanner(scene, sensor, options);
  // --bench times first returns (what bare Embree's closest hits compare with).
  ScanOptions firstOnly = options;
  firstOnly.returns = ScanReturns::First;
  std::optional<SweepScanner> firstScanner;
  if (r.bench) firstScanner.emplace(scene, sensor, firstOnly);
  for (int k = 0; k < r.sweeps; ++k) {
    const LidarRays rays = sweepRays(sensor, trajectory, k, sweepStartNs(r.startNs, k, period));
    // With an explicit start the sweep index only numbers the output; the rays' noise stays
    // a function of (seed, sweep, ray).
    ScanSweep sweep = scanner.scan(rays, image);
    if (image)
      writeRangeImage(paths[size_t(k)], sweep.image);
    else
      writePointCloud(paths[size_t(k)], sweep.cloud, writeOptions);
    if (!r.quiet)
      std::fprintf(stderr, "sweep %d/%d: %zu rays, %zu points, %.3f s -> %s\n", k + 1, r.sweeps,
                   sweep.rays, sweep.points, sweep.traceSeconds, paths[size_t(k)].c_str());
    if (r.bench) {
      const std::vector<TraceRay> traced = lidarTraceRays(rays, scene.renderOrigin());
      // Wall and CPU seconds (the process's: on a loaded machine the CPU time of a call is
      // the steadier measure of its work), best of 15 each, alternating.
      double best = 1e30, bestBare = 1e30, bestCpu = 1e30, bestBareCpu = 1e30;
      size_t bareHits = 0;
      for (int round = 0; round < 15; ++round) {
        double cpu = processCpuSeconds();
        ScanSweep timed = firstScanner->scan(rays);
        bestCpu = std::min(bestCpu, processCpuSeconds() - cpu);
        best = std::min(best, timed.traceSeconds);
        firstScanner->recycle(std::move(timed));
        cpu = processCpuSeconds();
        bestBare = std::min(bestBare, bareEmbreeSeconds(scene, traced, &bareHits));
        bestBareCpu = std::min(bestBareCpu, processCpuSeconds() - cpu);
      }
      // Making the sweep's rays (firing times, poses, directions), which the loop is given.
      double bestRays = 1e30;
      for (int round = 0; round < 5; ++round) {
        const auto t0 = Clock::now();
        sweepRays(sensor, trajectory, k, sweepStartNs(r.startNs, k, period));
        bestRays = std::min(bestRays, secondsSince(t0));
      }
      std::printf(
          "scan bench: %zu rays, %zu hits; scan loop %.4f s (%.2f Mpts/s), bare Embree %.4f s "
          "(%.2f Mrays/s), ratio %.3f; CPU s scan loop %.4f, bare Embree %.4f, ratio %.3f; "
          "rays made in %.4f s; %d threads, isa %s, %zu triangles\n",
          traced.size(), bareHits, best, double(traced.size()) / best * 1e-6, bestBare,
          double(traced.size()) / bestBare * 1e-6, bestBare / best, bestCpu, bestBareCpu,
          bestBareCpu / bestCpu, bestRays, threads, isa.c_str(), scene.stats().triangles);
    }
    scanner.recycle(std::move(sweep));
  }
}

void runScan(const ScanRequest& r) {
  // Everything that can be refused is refused before the scene loads.
  const PreparedScan prepared = prepareScan(r);
  const ThreadLimit threads(r.threads);
  const Device device;
  LoadedScene loaded = loadScene(device, scanSceneSpec(r.scene, r.options), r.quiet);
  writeScans(*loaded.scene, r, prepared, device.isaName(), threads.threads());
}

}  // namespace aperture::app
