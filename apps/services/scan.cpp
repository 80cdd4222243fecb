#include "apps/services/scan.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <type_traits>

#include "apps/services/render_options.h"
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

/// One surface along a ray, turned into a point's values.
/// Trivial (left unwritten when allocated): traceChunk clears `hit` of each of its slots, and
/// the rest is read only where `hit` is set.
struct Surface {
  glm::dvec3 point;  ///< in the frame asked for
  float range;       ///< metres, reported (with the beam's range offset and noise)
  float incidence, intensity;
  uint32_t geomId, primId, instance;
  uint32_t triangle;  ///< the stored triangle, for the face properties
  bool hit;
};

/// Rays per chunk of the parallel loop (fixed: the work of a chunk does not depend on threads).
constexpr size_t kScanChunk = 4096;
/// Noise index of surface k of ray i: distinct for every (ray, surface) of a sweep.
uint64_t noiseIndex(size_t ray, int surface) { return uint64_t(ray) * 64u + uint64_t(surface); }

struct SweepContext {
  const Scene& scene;
  const LidarSensor& sensor;
  const LidarRays& rays;
  const ScanOptions& options;
  Pose sweepStartFromWorld;
  std::vector<const MeshProperty*> reflectance;  ///< per object, or null
  std::vector<Pose> sensorFromWorld;             ///< per pose of `rays`
};

/// The values of the surface hit `h` of ray i, or a miss when noise drops it or the range falls
/// outside [minRange, maxRange].
Surface surfaceOf(const SweepContext& c, size_t i, const TraceHit& h, int k) {
  Surface s;
  s.hit = false;
  if (!h.hit()) return s;
  double range = double(h.t) + double(c.rays.rangeOffset[i]);
  if (c.options.noise.enabled()) {
    const std::optional<double> noisy =
        applyRangeNoise(c.options.noise, range, c.rays.sweep, noiseIndex(i, k));
    if (!noisy) return s;
    range = *noisy;
  }
  if (range < c.sensor.minRange || range > c.sensor.maxRange || range <= 0) return s;
  const double travel = range - double(c.rays.rangeOffset[i]);
  const glm::dvec3 world = c.rays.origin[i] + c.rays.direction[i] * travel;
  switch (c.options.frame) {
    case ScanFrame::Sensor:
      s.point = c.sensorFromWorld[c.rays.poseIndex[i]].apply(world);
      break;
    case ScanFrame::World:
      s.point = world;
      break;
    case ScanFrame::SweepStart:
      s.point = c.sweepStartFromWorld.apply(world);
      break;
  }
  s.hit = true;
  s.range = float(range);
  const glm::vec3 n = c.scene.normalFromMesh(h.geomId) * h.ng;
  const float len = glm::length(n);
  s.incidence = len > 0 ? std::fabs(glm::dot(n / len, glm::vec3(c.rays.direction[i]))) : 0.0f;
  double rho = 1.0;
  if (const MeshProperty* p = c.reflectance[h.geomId])
    rho = double(p->values[h.meshTriangle]) / 100.0;
  s.intensity = float(rho * double(s.incidence) / (range * range));
  s.geomId = h.geomId;
  s.primId = h.primId;
  const Mesh& mesh = c.scene.objectMesh(h.geomId);
  s.instance = c.scene.objectIds(h.geomId).instance +
               (mesh.faceGroups.empty() ? 0u : mesh.faceGroups[h.meshTriangle]);
  s.triangle = h.meshTriangle;
  return s;
}

/// The surfaces of rays [first, last): slot (i − first)·perRay + j, for perRay = maxSurfaces
/// with ScanReturns::All, else 1 (the selected one).
void traceChunk(const SweepContext& c, size_t first, size_t last, Surface* out,
                uint8_t* returnsOf) {
  const ScanOptions& o = c.options;
  const int passes = o.returns == ScanReturns::First ? 1 : o.maxSurfaces;
  const bool all = o.returns == ScanReturns::All;
  const size_t perRay = all ? size_t(o.maxSurfaces) : 1;
  for (size_t k = 0; k < (last - first) * perRay; ++k) out[k].hit = false;
  const glm::dvec3& renderOrigin = c.scene.renderOrigin();
  std::vector<TraceRay> batch(last - first);
  std::vector<size_t> rayOf(last - first);
  for (size_t i = first; i < last; ++i) {
    TraceRay& r = batch[i - first];
    r.org = glm::vec3(c.rays.origin[i] - renderOrigin);
    r.dir = glm::vec3(c.rays.direction[i]);
    r.tnear = c.rays.tnear[i];
    r.tfar = c.rays.tfar[i];
    rayOf[i - first] = i;
  }
  std::vector<int> found(last - first, 0);
  std::vector<float> best(last - first, -1.0f);
  for (int k = 0; k < passes && !batch.empty(); ++k) {
    const std::vector<TraceHit> hits = traceRays(c.scene, batch, 16);
    std::vector<TraceRay> next;
    std::vector<size_t> nextRay;
    for (size_t j = 0; j < hits.size(); ++j) {
      if (!hits[j].hit()) continue;
      const size_t i = rayOf[j];
      const size_t local = i - first;
      const Surface s = surfaceOf(c, i, hits[j], k);
      if (s.hit) {
        if (all) {
          out[local * perRay + size_t(found[local])] = s;
        } else if (o.returns == ScanReturns::Strongest) {
          if (s.intensity > best[local]) best[local] = s.intensity, out[local] = s;
        } else {
          out[local] = s;  // first (one pass) or last (the farthest found)
        }
        ++found[local];
      }
      if (k + 1 == passes) continue;
      TraceRay r = batch[j];
      r.tnear = std::max(std::nextafter(hits[j].t, std::numeric_limits<float>::infinity()),
                         hits[j].t + float(o.returnSeparation));
      if (r.tnear <= r.tfar) {
        next.push_back(r);
        nextRay.push_back(i);
      }
    }
    batch.swap(next);
    rayOf.swap(nextRay);
  }
  for (size_t local = 0; local < last - first; ++local) returnsOf[local] = uint8_t(found[local]);
}

PointType positionType(ScanFrame frame) {
  return frame == ScanFrame::World ? PointType::Float64 : PointType::Float32;
}

void storePosition(PointField& f, size_t at, double v) {
  if (f.type == PointType::Float64)
    f.as<double>()[at] = v;
  else
    f.as<float>()[at] = float(v);
}

uint32_t propertyValue(const Scene& scene, const Surface& s, const std::string& name) {
  const MeshProperty* p = scene.objectMesh(s.geomId).property(PropertyDomain::Face, name);
  return p ? p->values[s.triangle] : 0xFFFFFFFFu;
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

ScanSweep scanSweep(const Scene& scene, const LidarSensor& sensor, const LidarRays& rays,
                    const ScanOptions& options, bool rangeImage) {
  if (options.maxSurfaces < 1 || options.maxSurfaces > 64)
    throw Error(cat("surfaces per ray ", options.maxSurfaces, " is outside 1..64"));
  if (rangeImage && options.returns == ScanReturns::All)
    throw Error("a range image holds one return per ray: --returns all needs a point cloud");
  const auto t0 = Clock::now();
  SweepContext c{scene, sensor, rays, options, rays.sweepStartPose.inverse(), {}, {}};
  for (const Pose& p : rays.poses) c.sensorFromWorld.push_back(p.inverse());
  for (size_t o = 0; o < scene.objectCount(); ++o)
    c.reflectance.push_back(
        scene.objectMesh(unsigned(o)).property(PropertyDomain::Face, kReflectanceProperty));
  const size_t n = rays.size();
  const bool all = options.returns == ScanReturns::All;
  const size_t perRay = all ? size_t(options.maxSurfaces) : 1;
  static_assert(std::is_trivially_default_constructible<Surface>::value, "left unwritten");
  LargeBuffer<Surface> surfaces;
  resizeOnHugePages(surfaces, n * perRay);
  std::vector<uint8_t> returnsOf(n);
  for (size_t i = 0; i < n; ++i)
    if (rays.timeNs[i] < 0 || rays.timeNs[i] > int64_t(UINT32_MAX))
      throw Error(cat(sensor.source.path, ": ray ", i, " fires ", rays.timeNs[i],
                      " ns after the sweep's start, past the uint32 time field (4.29 s)"));
  // Trace in fixed chunks, counting each chunk's points; then every chunk writes its points
  // from the offset the counts before it give (the cloud is the same on any thread count).
  const size_t chunks = (n + kScanChunk - 1) / kScanChunk;
  std::vector<size_t> offset(chunks + 1, 0);
  parallelForChunks(n, kScanChunk, [&](size_t chunk, size_t first, size_t last) {
    traceChunk(c, first, last, surfaces.data() + first * perRay, returnsOf.data() + first);
    size_t hits = 0;
    for (size_t k = first * perRay; k < last * perRay; ++k) hits += surfaces[k].hit ? 1 : 0;
    offset[chunk + 1] = hits;
  });
  for (size_t k = 0; k < chunks; ++k) offset[k + 1] += offset[k];

  ScanSweep result;
  result.rays = n;
  const size_t points = offset[chunks];
  PointCloud& cloud = result.cloud;
  cloud.size = points;
  cloud.startSeconds = double(rays.sweepStartNs) * 1e-9;
  // Every field is written for every point below: left unwritten here.
  const PointType xyzType = positionType(options.frame);
  cloud.addField(pf::kX, xyzType, false);
  cloud.addField(pf::kY, xyzType, false);
  cloud.addField(pf::kZ, xyzType, false);
  auto* range = cloud.add<float>(pf::kRange, PointType::Float32, false);
  auto* time = cloud.add<uint32_t>(pf::kTime, PointType::UInt32, false);
  auto* ring = cloud.add<uint16_t>(pf::kRing, PointType::UInt16, false);
  auto* column = cloud.add<uint32_t>(pf::kColumn, PointType::UInt32, false);
  auto* azimuth = cloud.add<float>(pf::kAzimuth, PointType::Float32, false);
  auto* incidence = cloud.add<float>(pf::kIncidence, PointType::Float32, false);
  auto* intensity = cloud.add<float>(pf::kIntensity, PointType::Float32, false);
  auto* primid = cloud.add<uint32_t>(pf::kPrimId, PointType::UInt32, false);
  auto* geomid = cloud.add<uint32_t>(pf::kGeomId, PointType::UInt32, false);
  auto* instance = cloud.add<uint32_t>(pf::kInstance, PointType::UInt32, false);
  uint8_t* returnNumber =
      all ? cloud.add<uint8_t>(pf::kReturnNumber, PointType::UInt8, false) : nullptr;
  uint8_t* returns = all ? cloud.add<uint8_t>(pf::kReturns, PointType::UInt8, false) : nullptr;
  std::vector<uint32_t*> properties;
  for (const std::string& name : options.faceProperties) {
    if (cloud.find(name))
      throw Error(cat("face property '", name, "' has the name of a standard point field"));
    properties.push_back(cloud.add<uint32_t>(name, PointType::UInt32, false));
  }
  // The fields themselves are taken once every field is added: adding one may move the others
  // (their values stay where they are, which the pointers above hold).
  PointField* xyz[3] = {cloud.find(pf::kX), cloud.find(pf::kY), cloud.find(pf::kZ)};
  std::vector<const MeshProperty*> propertyOf;  // object-major: [object · P + p]
  for (size_t o = 0; o < scene.objectCount(); ++o)
    for (const std::string& name : options.faceProperties)
      propertyOf.push_back(scene.objectMesh(unsigned(o)).property(PropertyDomain::Face, name));
  const size_t P = options.faceProperties.size();
  parallelForChunks(n, kScanChunk, [&](size_t chunk, size_t first, size_t last) {
    size_t at = offset[chunk];
    for (size_t i = first; i < last; ++i)
      for (size_t j = 0; j < perRay; ++j) {
        const Surface& s = surfaces[i * perRay + j];
        if (!s.hit) continue;
        for (int a = 0; a < 3; ++a) storePosition(*xyz[a], at, s.point[a]);
        range[at] = s.range;
        time[at] = uint32_t(rays.timeNs[i]);
        ring[at] = uint16_t(rays.ring[i]);
        column[at] = rays.column[i];
        azimuth[at] = float(double(rays.azimuthDeg[i]) * M_PI / 180.0);
        incidence[at] = s.incidence;
        intensity[at] = s.intensity;
        primid[at] = s.primId;
        geomid[at] = s.geomId;
        instance[at] = s.instance;
        if (all) {
          returnNumber[at] = uint8_t(j + 1);
          returns[at] = returnsOf[i];
        }
        for (size_t p = 0; p < P; ++p) {
          const MeshProperty* m = propertyOf[s.geomId * P + p];
          properties[p][at] = m ? m->values[s.triangle] : TraceHit::kNoHit;
        }
        ++at;
      }
  });
  result.points = points;

  if (rangeImage) {
    RangeImage& img = result.image;
    img.rows = std::max(1, rays.rows);
    img.columns = std::max(1, rays.columns);
    img.pixelShiftByRow = sensor.pixelShiftByRow;
    auto* RANGE = img.addChannel("RANGE", PointType::UInt32).as<uint32_t>();
    auto* metres = img.addChannel(pf::kRange, PointType::Float32).as<float>();
    auto* imgIntensity = img.addChannel(pf::kIntensity, PointType::Float32).as<float>();
    auto* imgIncidence = img.addChannel(pf::kIncidence, PointType::Float32).as<float>();
    auto* imgTime = img.addChannel(pf::kTime, PointType::UInt32).as<uint32_t>();
    float* imgXyz[3] = {img.addChannel(pf::kX, PointType::Float32).as<float>(),
                        img.addChannel(pf::kY, PointType::Float32).as<float>(),
                        img.addChannel(pf::kZ, PointType::Float32).as<float>()};
    auto* imgPrim = img.addChannel(pf::kPrimId, PointType::UInt32).as<uint32_t>();
    auto* imgGeom = img.addChannel(pf::kGeomId, PointType::UInt32).as<uint32_t>();
    auto* imgInstance = img.addChannel(pf::kInstance, PointType::UInt32).as<uint32_t>();
    std::vector<uint32_t*> imgProps;
    for (const std::string& name : options.faceProperties)
      imgProps.push_back(img.addChannel(name, PointType::UInt32).as<uint32_t>());
    const size_t pixels = size_t(img.rows) * size_t(img.columns);
    std::fill(imgPrim, imgPrim + pixels, TraceHit::kNoHit);
    std::fill(imgGeom, imgGeom + pixels, TraceHit::kNoHit);
    std::fill(imgInstance, imgInstance + pixels, TraceHit::kNoHit);
    for (uint32_t* p : imgProps) std::fill(p, p + pixels, TraceHit::kNoHit);
    for (size_t i = 0; i < n; ++i) {
      const size_t row = sensor.kind == LidarKind::Spinning ? rays.ring[i] : 0;
      const size_t col = sensor.kind == LidarKind::Spinning ? rays.column[i] : i;
      if (row >= size_t(img.rows) || col >= size_t(img.columns)) continue;
      const size_t px = row * size_t(img.columns) + col;
      imgTime[px] = uint32_t(rays.timeNs[i]);
      const Surface& s = surfaces[i];
      if (!s.hit) continue;
      RANGE[px] = uint32_t(std::lround(double(s.range) * 1000.0));
      metres[px] = s.range;
      imgIntensity[px] = s.intensity;
      imgIncidence[px] = s.incidence;
      for (int a = 0; a < 3; ++a) imgXyz[a][px] = float(s.point[a]);
      imgPrim[px] = s.primId;
      imgGeom[px] = s.geomId;
      imgInstance[px] = s.instance;
      for (size_t p = 0; p < imgProps.size(); ++p)
        imgProps[p][px] = propertyValue(scene, s, options.faceProperties[p]);
    }
  }
  result.traceSeconds = secondsSince(t0);
  return result;
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
  SceneSpec spec = scene.spec();
  auto want = [&](const std::string& name) {
    const PropertyAov p{PropertyDomain::Face, name};
    if (std::find(spec.properties.begin(), spec.properties.end(), p) == spec.properties.end())
      spec.properties.push_back(p);
  };
  if (everyMeshHasFaceProperty(spec, kReflectanceProperty)) want(kReflectanceProperty);
  for (const std::string& name : options.faceProperties) want(name);
  return spec;
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
  if (r.options.maxSurfaces < 1 || r.options.maxSurfaces > 64)
    throw Error(cat("--surfaces ", r.options.maxSurfaces, " is outside 1..64"));
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
        r.startNs ? *r.startNs + int64_t(k) * period : trajectory.startNs() + int64_t(k) * period;
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
  for (int k = 0; k < r.sweeps; ++k) {
    const LidarRays rays = sweepRays(
        sensor, trajectory, k,
        r.startNs ? std::optional<int64_t>(*r.startNs + int64_t(k) * period) : std::nullopt);
    // With an explicit start the sweep index only numbers the output; the rays' noise stays
    // a function of (seed, sweep, ray).
    const ScanSweep sweep = scanSweep(scene, sensor, rays, r.options, image);
    if (image)
      writeRangeImage(paths[size_t(k)], sweep.image);
    else
      writePointCloud(paths[size_t(k)], sweep.cloud, writeOptions);
    if (!r.quiet)
      std::fprintf(stderr, "sweep %d/%d: %zu rays, %zu points, %.3f s -> %s\n", k + 1, r.sweeps,
                   sweep.rays, sweep.points, sweep.traceSeconds, paths[size_t(k)].c_str());
    if (r.bench) {
      const std::vector<TraceRay> traced = lidarTraceRays(rays, scene.renderOrigin());
      ScanOptions firstOnly = r.options;
      firstOnly.returns = ScanReturns::First;
      double best = 1e30, bestBare = 1e30;
      size_t bareHits = 0;
      for (int round = 0; round < 15; ++round) {
        best = std::min(best, scanSweep(scene, sensor, rays, firstOnly, false).traceSeconds);
        bestBare = std::min(bestBare, bareEmbreeSeconds(scene, traced, &bareHits));
      }
      std::printf(
          "scan bench: %zu rays, %zu hits; scan loop %.4f s (%.2f Mpts/s), bare Embree %.4f s "
          "(%.2f Mrays/s), ratio %.3f; %d threads, isa %s, %zu triangles\n",
          traced.size(), bareHits, best, double(traced.size()) / best * 1e-6, bestBare,
          double(traced.size()) / bestBare * 1e-6, bestBare / best, threads, isa.c_str(),
          scene.stats().triangles);
    }
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
