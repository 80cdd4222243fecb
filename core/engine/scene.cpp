#include "core/engine/scene.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <mutex>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/vector_kernel.h"

namespace aperture {

struct Device::State {
  std::mutex mutex;
  std::string pendingError;  // first error since the last check()
  std::atomic<long long> bytes{0};
};

namespace {

const char* errorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE:
      return "none";
    case RTC_ERROR_UNKNOWN:
      return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
  }
  return "unrecognised error";
}

// Called by Embree on any thread; an exception must not cross Embree's C frames, so the
// message is stored and thrown by the next Device::check().
void onEmbreeError(void* user, RTCError code, const char* str) {
  auto* state = static_cast<Device::State*>(user);
  std::lock_guard<std::mutex> lock(state->mutex);
  if (state->pendingError.empty())
    state->pendingError = cat("Embree: ", errorName(code), str ? cat(": ", str) : std::string());
}

bool onEmbreeMemory(void* user, ssize_t bytes, bool /*post*/) {
  static_cast<Device::State*>(user)->bytes += bytes;
  return true;
}

RTCBuildQuality toEmbree(BvhQuality q) {
  switch (q) {
    case BvhQuality::Low:
      return RTC_BUILD_QUALITY_LOW;
    case BvhQuality::Medium:
      return RTC_BUILD_QUALITY_MEDIUM;
    case BvhQuality::High:
      return RTC_BUILD_QUALITY_HIGH;
  }
  return RTC_BUILD_QUALITY_HIGH;
}

}  // namespace

Device::Device(const std::string& givenConfig) : state_(std::make_unique<State>()) {
  // APERTURE_EMBREE_CONFIG (e.g. "isa=sse4.2") applies when the caller gives none: it pins
  // Embree's kernels so images are bit-comparable across CPUs.
  const char* fromEnvironment = std::getenv("APERTURE_EMBREE_CONFIG");
  // Its twin for aperture's own kernels, APERTURE_KERNEL_ISA, is read here too, so that a bad
  // value is reported before any work (core/util/vector_kernel.h).
  activeKernelIsa();
  const std::string config =
      givenConfig.empty() && fromEnvironment ? std::string(fromEnvironment) : givenConfig;
  device_ = rtcNewDevice(config.empty() ? nullptr : config.c_str());
  if (!device_)
    throw Error(cat("Embree: cannot create a device (config '", config,
                    "'): ", errorName(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(device_, onEmbreeError, state_.get());
  rtcSetDeviceMemoryMonitorFunction(device_, onEmbreeMemory, state_.get());
}

Device::~Device() {
  if (device_) rtcReleaseDevice(device_);
}

void Device::check(const char* what) const {
  std::string message;
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    message.swap(state_->pendingError);
  }
  if (!message.empty()) throw Error(cat(message, " (during ", what, ")"));
}

long long Device::memoryBytes() const { return state_->bytes.load(); }

std::string Device::isaName() const {
  if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) return "AVX512";
  if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)) return "AVX2";
  if (rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED)) return "SSE4.2";
  return "unknown";
}

BvhQuality parseBvhQuality(const std::string& name) {
  if (name == "low") return BvhQuality::Low;
  if (name == "medium") return BvhQuality::Medium;
  if (name == "high") return BvhQuality::High;
  throw Error(cat("unknown BVH quality '", name, "' (known: low, medium, high)"));
}

const char* bvhQualityName(BvhQuality q) {
  switch (q) {
    case BvhQuality::Low:
      return "low";
    case BvhQuality::Medium:
      return "medium";
    case BvhQuality::High:
      return "high";
  }
  return "?";
}

size_t checkedBvhChunkTriangles(long long triangles, const std::string& where) {
  if (triangles != 0 && (triangles < (long long)kMinBvhChunkTriangles || triangles > (1ll << 32)))
    throw Error(cat(where, " ", triangles, ": must be 0 (one BVH per mesh) or at least ",
                    kMinBvhChunkTriangles, " triangles (at most 2^32)"));
  return size_t(triangles);
}

std::vector<uint32_t> centroidCells(const Mesh& m, const uint32_t* indices, size_t triangles) {
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  const glm::vec3 scale = float(kCentroidGrid) / glm::max(hi - lo, glm::vec3(1e-30f));
  std::vector<uint32_t> cells(triangles);
  parallelFor(triangles, size_t(1) << 18, [&](size_t begin, size_t end) {
    for (size_t t = begin; t < end; ++t) {
      const uint32_t* corner = &indices[3 * t];
      const glm::vec3 centroid =
          (m.vertex(corner[0]) + m.vertex(corner[1]) + m.vertex(corner[2])) / 3.0f;
      if (!std::isfinite(centroid.x + centroid.y + centroid.z)) {
        cells[t] = kNoCell;
        continue;
      }
      const glm::ivec3 c = glm::clamp(glm::ivec3((centroid - lo) * scale), 0, kCentroidGrid - 1);
      cells[t] = (uint32_t(c.z) * kCentroidGrid + uint32_t(c.y)) * kCentroidGrid + uint32_t(c.x);
    }
  });
  return cells;
}

double chunksPerCell(const std::vector<uint32_t>& cells, size_t chunkTriangles) {
  constexpr size_t kCells = size_t(kCentroidGrid) * kCentroidGrid * kCentroidGrid;
  constexpr size_t kWords = kCells / 64;
  std::vector<uint32_t> chunksIn(kCells, 0);  // per cell, the chunks with a centroid in it
  std::mutex merge;
  parallelForChunks(cells.size(), chunkTriangles, [&](size_t, size_t begin, size_t end) {
    std::vector<uint64_t> bits(kWords, 0);  // this chunk's cells
    for (size_t t = begin; t < end; ++t)
      if (cells[t] != kNoCell) bits[cells[t] / 64] |= uint64_t(1) << (cells[t] % 64);
    std::lock_guard<std::mutex> lock(merge);
    for (size_t w = 0; w < kWords; ++w)
      for (uint64_t b = bits[w]; b != 0; b &= b - 1)
        ++chunksIn[64 * w + size_t(__builtin_ctzll(b))];
  });
  uint64_t occupied = 0, memberships = 0;
  for (uint32_t n : chunksIn) occupied += n > 0, memberships += n;
  return occupied ? double(memberships) / double(occupied) : 1.0;
}

double chunksPerCell(const Mesh& m, const uint32_t* indices, size_t triangles,
                     size_t chunkTriangles) {
  return chunksPerCell(centroidCells(m, indices, triangles), chunkTriangles);
}

namespace {

std::vector<SceneObject> untransformed(const std::vector<const Mesh*>& meshes) {
  std::vector<SceneObject> objects;
  for (const Mesh* m : meshes) {
    if (m->anchor != meshes.front()->anchor)
      throw Error(cat("scene: mesh '", m->name, "' has a different anchor than '",
                      meshes.front()->name, "'"));
    objects.push_back({m, glm::dmat4(1.0)});
  }
  return objects;
}

/// A triangle geometry over `triangles` triangles of `m` whose vertex indices start at
/// `indices` (the mesh's, a subset's, or a chunk of either); both buffers are shared.
RTCGeometry triangleGeometry(const Device& device, const Mesh& m, const uint32_t* indices,
                             size_t triangles, RTCBuildQuality quality) {
  // Embree may read 16 bytes at the last vertex: the loader pads positions for that.
  APERTURE_CHECK_OP(m.positions.size(), >=, 3 * m.vertexCount + kVertexPaddingFloats - 1);
  RTCGeometry geom = rtcNewGeometry(device.handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geom, quality);
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m.positions.data(),
                             0, 3 * sizeof(float), m.vertexCount);
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, indices, 0,
                             3 * sizeof(uint32_t), triangles);
  rtcCommitGeometry(geom);
  device.check(cat("adding mesh '", m.name, "'").c_str());
  return geom;
}

RTCScene newEmbreeScene(const Device& device, RTCSceneFlags flags, RTCBuildQuality quality) {
  RTCScene s = rtcNewScene(device.handle());
  device.check("rtcNewScene");
  rtcSetSceneFlags(s, flags);
  rtcSetSceneBuildQuality(s, quality);
  return s;
}

/// An instance of `sub` under render-space transform `xf`, attached to `scene` as `id`.
void attachInstance(const Device& device, RTCScene scene, RTCScene sub, const glm::mat4& xf,
                    unsigned id) {
  RTCGeometry inst = rtcNewGeometry(device.handle(), RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(inst, sub);
  rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &xf[0][0]);
  rtcCommitGeometry(inst);
  rtcAttachGeometryByID(scene, inst, id);
  rtcReleaseGeometry(inst);
}

}  // namespace

glm::dvec3 renderOriginOf(const std::vector<SceneObject>& objects) {
  const SceneObject& first = objects.front();
  return glm::dvec3(first.worldFromMesh * glm::dvec4(first.mesh->anchor, 1.0));
}

std::vector<bool> attachedDirectly(const std::vector<SceneObject>& objects) {
  std::vector<bool> direct(objects.size(), false);
  if (objects.empty()) return direct;
  const glm::dvec3 origin = renderOriginOf(objects);
  std::map<const Mesh*, size_t> uses;
  for (const SceneObject& o : objects) ++uses[o.mesh];
  for (size_t k = 0; k < objects.size(); ++k) {
    const SceneObject& o = objects[k];
    direct[k] = uses[o.mesh] == 1 && o.worldFromMesh == glm::dmat4(1.0) && o.mesh->anchor == origin;
  }
  return direct;
}

Scene::Scene(const Device& device, const std::vector<const Mesh*>& meshes,
             const BuildOptions& options)
    : Scene(device, untransformed(meshes), options) {}

Scene::Scene(const Device& device, const std::vector<SceneObject>& objects,
             const BuildOptions& options)
    : device_(device), options_(options) {
  if (objects.empty()) throw Error("scene: no meshes");
  renderOrigin_ = renderOriginOf(objects);
  objects_ = objects;
  const std::vector<bool> direct = attachedDirectly(objects);

  const long long bytesBefore = device.memoryBytes();
  const auto start = std::chrono::steady_clock::now();
  const RTCBuildQuality quality = toEmbree(options.quality);
  int flagBits = RTC_SCENE_FLAG_NONE;
  if (options.robust) flagBits |= RTC_SCENE_FLAG_ROBUST;
  if (options.compact) flagBits |= RTC_SCENE_FLAG_COMPACT;
  if (options.contextFilter) flagBits |= RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION;
  const RTCSceneFlags flags = RTCSceneFlags(flagBits);
  const size_t chunkTriangles = options.effectiveChunkTriangles();
  scene_ = newEmbreeScene(device, flags, quality);
  std::map<const Mesh*, RTCScene> built;  // sub-scene of each instanced mesh
  normalFromMesh_.assign(objects.size(), glm::mat3(1.0f));
  for (const SceneObject& o : objects) {
    objectMeshes_.push_back(o.mesh);
    reordered_ = reordered_ || !o.mesh->sourceTriangles.empty();
  }
  for (const SceneObject& o : objects)
    if (o.subset) primIdMaps_.assign(objects.size(), nullptr);
  for (size_t k = 0; k < objects.size(); ++k) {
    const Mesh& m = *objects[k].mesh;
    const TriangleSubset* subset = objects[k].subset;
    const size_t placed = subset ? subset->triangleCount() : m.triangleCount();
    stats_.triangles += placed;
    stats_.culledTriangles += m.triangleCount() - placed;
    if (subset) {
      APERTURE_CHECK_OP(subset->indices.size(), ==, 3 * subset->primIds.size());
      primIdMaps_[k] = subset->primIds.data();
      // Nothing of this object is kept: leave its geomID unused.
      if (placed == 0) continue;
    }
    const LargeBuffer<uint32_t>& indices = subset ? subset->indices : m.indices;
    if (direct[k] && chunkTriangles > 0 && placed > chunkTriangles) {
      const double shared = chunksPerCell(m, indices.data(), placed, chunkTriangles);
      stats_.chunksPerCell = std::max(stats_.chunksPerCell, shared);
      if (shared <= options.maxChunksPerCell) {
        attachChunks(unsigned(k), m, indices, chunkTriangles, quality, flags);
        stats_.uniqueTriangles += placed;
        continue;
      }
    }
    if (direct[k]) {
      RTCGeometry geom = triangleGeometry(device, m, indices.data(), placed, quality);
      rtcAttachGeometryByID(scene_, geom, unsigned(k));
      rtcReleaseGeometry(geom);
      stats_.uniqueTriangles += placed;
      continue;
    }
    auto it = built.find(&m);
    if (it == built.end()) {
      RTCScene sub = buildSubScene(m, indices.data(), placed, quality, flags,
                                   cat("building the BVH of mesh '", m.name, "'"));
      it = built.emplace(&m, sub).first;
      stats_.uniqueTriangles += placed;
    }
    // Render space from mesh-local space, composed in double: T(−origin) · M · T(anchor).
    const glm::dmat4 renderFromLocal = glm::translate(glm::dmat4(1.0), -renderOrigin_) *
                                       objects[k].worldFromMesh *
                                       glm::translate(glm::dmat4(1.0), m.anchor);
    attachInstance(device, scene_, it->second, glm::mat4(renderFromLocal), unsigned(k));
    device.check(cat("instancing mesh '", m.name, "'").c_str());
    normalFromMesh_[k] = glm::mat3(glm::transpose(glm::inverse(glm::dmat3(renderFromLocal))));
    ++instanced_;
  }
  rtcCommitScene(scene_);
  device.check("rtcCommitScene (BVH build)");
  RTCBounds b;
  rtcGetSceneBounds(scene_, &b);
  box_ = paddedSceneBox({b.lower_x, b.lower_y, b.lower_z}, {b.upper_x, b.upper_y, b.upper_z});
  stats_.buildSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats_.embreeBytes = device.memoryBytes() - bytesBefore;
}

const Occupancy* Scene::occupancy() const {
  std::call_once(occupancyOnce_, [this] {
    if (box_) occupancy_ = occupancyOf(objects_, renderOrigin_, *box_);
  });
  return occupancy_ ? &*occupancy_ : nullptr;
}

RTCScene Scene::buildSubScene(const Mesh& m, const uint32_t* indices, size_t triangles,
                              RTCBuildQuality quality, RTCSceneFlags flags,
                              const std::string& what) {
  RTCScene sub = newEmbreeScene(device_, flags, quality);
  subScenes_.push_back(sub);
  RTCGeometry geom = triangleGeometry(device_, m, indices, triangles, quality);
  rtcAttachGeometryByID(sub, geom, 0);
  rtcReleaseGeometry(geom);
  rtcCommitScene(sub);
  device_.check(what.c_str());
  return sub;
}

// Each chunk's BVH is committed before the next chunk's geometry is made, so Embree holds
// the primitive references of one chunk at a time. Chunk 0's instance takes the object's own
// geomID; the others take geomIDs after the last object's.
void Scene::attachChunks(unsigned object, const Mesh& m, const LargeBuffer<uint32_t>& indices,
                         size_t chunkTriangles, RTCBuildQuality quality, RTCSceneFlags flags) {
  const size_t triangles = indices.size() / 3;
  const size_t chunks = (triangles + chunkTriangles - 1) / chunkTriangles;
  const size_t firstExtraId = std::max(objectMeshes_.size(), chunkSlots_.size());
  chunkSlots_.resize(firstExtraId + chunks - 1);
  for (size_t c = 0; c < chunks; ++c) {
    const size_t first = c * chunkTriangles;
    const size_t count = std::min(chunkTriangles, triangles - first);
    RTCScene sub = buildSubScene(m, indices.data() + 3 * first, count, quality, flags,
                                 cat("building the BVH of chunk ", c, " of mesh '", m.name, "'"));
    const unsigned id = c == 0 ? object : unsigned(firstExtraId + c - 1);
    attachInstance(device_, scene_, sub, glm::mat4(1.0f), id);
    device_.check(cat("placing chunk ", c, " of mesh '", m.name, "'").c_str());
    chunkSlots_[id] = {object, uint32_t(first)};
  }
  stats_.chunks += chunks;
}

void Scene::resolveChunkHits(unsigned* geomID, unsigned* primID, unsigned* instID, size_t n) const {
  const size_t ids = chunkSlots_.size();
  for (size_t k = 0; k < n; ++k) {
    const unsigned inst = instID[k];
    if (inst >= ids || chunkSlots_[inst].object == RTC_INVALID_GEOMETRY_ID) continue;
    geomID[k] = chunkSlots_[inst].object;
    primID[k] += chunkSlots_[inst].firstPrim;
    instID[k] = RTC_INVALID_GEOMETRY_ID;
  }
}

Scene::~Scene() {
  if (scene_) rtcReleaseScene(scene_);
  for (RTCScene s : subScenes_) rtcReleaseScene(s);
}

}  // namespace aperture
