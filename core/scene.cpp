#include "core/scene.h"

#include <atomic>
#include <chrono>
#include <mutex>

#include "core/error.h"

namespace aperture {

struct Device::State {
  std::mutex mutex;
  std::string pendingError;  // first error since the last check()
  std::atomic<long long> bytes{0};
};

namespace {

const char* errorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "none";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
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
    case BvhQuality::Low: return RTC_BUILD_QUALITY_LOW;
    case BvhQuality::Medium: return RTC_BUILD_QUALITY_MEDIUM;
    case BvhQuality::High: return RTC_BUILD_QUALITY_HIGH;
  }
  return RTC_BUILD_QUALITY_HIGH;
}

}  // namespace

Device::Device(const std::string& config) : state_(std::make_unique<State>()) {
  device_ = rtcNewDevice(config.empty() ? nullptr : config.c_str());
  if (!device_)
    throw Error(cat("Embree: cannot create a device (config '", config, "'): ",
                    errorName(rtcGetDeviceError(nullptr))));
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
    case BvhQuality::Low: return "low";
    case BvhQuality::Medium: return "medium";
    case BvhQuality::High: return "high";
  }
  return "?";
}

Scene::Scene(const Device& device, const std::vector<const Mesh*>& meshes,
             const BuildOptions& options)
    : device_(device), options_(options) {
  if (meshes.empty()) throw Error("scene: no meshes");
  renderOrigin_ = meshes.front()->anchor;
  for (const Mesh* m : meshes)
    if (m->anchor != renderOrigin_)
      throw Error(cat("scene: mesh '", m->name, "' has a different anchor than '",
                      meshes.front()->name, "'"));
  const long long bytesBefore = device.memoryBytes();
  const auto start = std::chrono::steady_clock::now();
  scene_ = rtcNewScene(device.handle());
  device.check("rtcNewScene");
  int flags = RTC_SCENE_FLAG_NONE;
  if (options.robust) flags |= RTC_SCENE_FLAG_ROBUST;
  if (options.compact) flags |= RTC_SCENE_FLAG_COMPACT;
  rtcSetSceneFlags(scene_, RTCSceneFlags(flags));
  rtcSetSceneBuildQuality(scene_, toEmbree(options.quality));
  for (size_t k = 0; k < meshes.size(); ++k) {
    const Mesh& m = *meshes[k];
    // Embree may read 16 bytes at the last vertex: the loader pads positions for that.
    APERTURE_CHECK_OP(m.positions.size(), >=, 3 * m.vertexCount + kVertexPaddingFloats - 1);
    RTCGeometry geom = rtcNewGeometry(device.handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, toEmbree(options.quality));
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                               m.positions.data(), 0, 3 * sizeof(float), m.vertexCount);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                               m.indices.data(), 0, 3 * sizeof(uint32_t), m.triangleCount());
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene_, geom, unsigned(k));
    rtcReleaseGeometry(geom);
    device.check(cat("adding mesh '", m.name, "'").c_str());
    stats_.triangles += m.triangleCount();
  }
  rtcCommitScene(scene_);
  device.check("rtcCommitScene (BVH build)");
  stats_.buildSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats_.embreeBytes = device.memoryBytes() - bytesBefore;
}

Scene::~Scene() {
  if (scene_) rtcReleaseScene(scene_);
}

}  // namespace aperture
