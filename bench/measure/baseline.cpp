#include "bench/measure/baseline.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include "core/engine/packet.h"
#include "core/util/parallel.h"
#include "core/util/vector_kernel.h"

namespace aperture {

namespace {

/// Whether `d` is a pinhole perspective camera without a clip: the rays the minimal
/// generation reproduces.
bool plainPinhole(const CameraDescription& d) {
  if (d.type != "perspective" || d.spp != 1) return false;
  for (const auto& [name, value] : d.extra)
    if (name == "clip" || name == "aperture_radius") return false;
  return true;
}

/// The 16 rays of the 4x4 block at (x0, y0): direction normalize(corner + j·du + i·dv) in
/// float, origin the eye; lanes outside the image are masked off.
void pinholeBlock(const glm::vec3& eye, const glm::vec3& corner, const glm::vec3& du,
                  const glm::vec3& dv, int x0, int y0, int width, int height, RTCRay16& r,
                  int* valid) {
  APERTURE_LANE_LOOP
  for (int k = 0; k < 16; ++k) {
    const LanePixel px = lanePixel(x0, y0, 4, k);
    const float j = float(px.column), i = float(px.row);
    const float x = corner.x + j * du.x + i * dv.x;
    const float y = corner.y + j * du.y + i * dv.y;
    const float z = corner.z + j * du.z + i * dv.z;
    const float inv = 1.0f / std::sqrt(x * x + y * y + z * z);
    r.org_x[k] = eye.x, r.org_y[k] = eye.y, r.org_z[k] = eye.z;
    r.dir_x[k] = x * inv, r.dir_y[k] = y * inv, r.dir_z[k] = z * inv;
    // Lanes outside the image get the empty segment [1, 0] too (sealLanes, core/engine/packet.h):
    // without a native 16-wide kernel Embree traces the packet as a stream, mask ignored.
    const bool in = px.inImage(width, height);
    r.tnear[k] = in ? 0.0f : 1.0f, r.tfar[k] = in ? INFINITY : 0.0f, r.time[k] = 0.0f;
    r.mask[k] = 0xFFFFFFFFu, r.id[k] = unsigned(k), r.flags[k] = 0;
    valid[k] = in ? -1 : 0;
  }
}

/// Lanes of a traced packet that were active and hit.
uint64_t packetHits(const RTCRayHit16& packet, const int* valid) {
  uint64_t n = 0;
  for (int k = 0; k < 16; ++k)
    n += valid[k] != 0 && packet.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
  return n;
}

}  // namespace

BaselineApi parseBaselineApi(const std::string& text, const char* flag) {
  for (BaselineApi api : {BaselineApi::Packet16, BaselineApi::StreamNM, BaselineApi::Stream1M})
    if (text == baselineApiName(api)) return api;
  throw Error(cat(flag, ": '", text, "' is not an Embree API of the baseline; choose packet16, ",
                  "stream-nm or stream-1m"));
}

const char* baselineApiName(BaselineApi api) {
  switch (api) {
    case BaselineApi::StreamNM:
      return "stream-nm";
    case BaselineApi::Stream1M:
      return "stream-1m";
    default:
      return "packet16";
  }
}

BaselineTracer::BaselineTracer(const Camera& camera, int width, int height, int tileSize,
                               BaselineApi api)
    : width_(width), height_(height), api_(api) {
  const CameraDescription d = camera.describe();
  pinhole_ = plainPinhole(d);
  if (pinhole_) {
    // Image-plane centre of pixel (0, 0) and the steps to the next column and row, from the
    // description (the screen window at z = 1 scaled to the plane at distance d), in double.
    const glm::dvec2 centre = d.screenWindowCenter * d.d;
    const double u0 = centre.x + (0.5 / width - 0.5) * d.vw;
    const double v0 = centre.y - (0.5 / height - 0.5) * d.vh;
    p_.eye = camera.renderEye();
    p_.corner = glm::vec3(u0 * d.u + v0 * d.v - d.d * d.w);
    p_.du = glm::vec3((d.vw / width) * d.u);
    p_.dv = glm::vec3(-(d.vh / height) * d.v);
  }
  const int tilesX = (width + tileSize - 1) / tileSize;
  const int tilesY = (height + tileSize - 1) / tileSize;
  alignas(64) RTCRayHit16 packet;
  RayLanes lanes = rayLanes<16>(packet);
  for (int tile = 0; tile < tilesX * tilesY; ++tile) {
    const int x0 = (tile % tilesX) * tileSize, y0 = (tile / tilesX) * tileSize;
    const Tile t{x0, y0, std::min(x0 + tileSize, width), std::min(y0 + tileSize, height),
                 rays16_.size()};
    rays_ += uint64_t(t.x1 - t.x0) * uint64_t(t.y1 - t.y0);
    tiles_.push_back(t);
    if (pinhole_) continue;
    for (int by = t.y0; by < t.y1; by += 4)
      for (int bx = t.x0; bx < t.x1; bx += 4) {
        ValidMask valid;
        const PacketRequest req{bx, by, 4, 4, PacketRequest::kCentreRay};
        camera.generate(req, lanes, valid.lanes);
        for (int k = 0; k < 16; ++k) {
          const bool inImage = req.inImage(k, width, height);
          // Pixels without a ray (outside a fisheye's circle) are not traced or counted.
          if (inImage && valid.lanes[k] == 0) --rays_;
          if (!inImage) valid.lanes[k] = 0;
        }
        // Traced as stored: lanes without a ray, outside the image or that Embree cannot
        // take are sealed once here (a traceable lane outside the image stays uncounted).
        const auto before = std::count_if(valid.lanes, valid.lanes + 16, [](int v) { return v; });
        rays_ -= uint64_t(before - sealLanes<16>(valid.lanes, lanes));
        rays16_.push_back(packet.ray);
        valid_.push_back(valid);
      }
  }
}

std::string BaselineTracer::rayGeneration() const {
  return pinhole_ ? "float pinhole in the loop" : "pre-generated";
}

void BaselineTracer::pinholeRays(int x0, int y0, RTCRay16& rays, int* valid) const {
  runKernel<&pinholeBlock>(p_.eye, p_.corner, p_.du, p_.dv, x0, y0, width_, height_, rays, valid);
}

void BaselineTracer::traceTilePinhole(const Scene& scene, const Tile& t, RTCIntersectContext& ctx,
                                      uint64_t* hits) const {
  alignas(64) RTCRayHit16 packet;
  alignas(64) int valid[16];
  for (int by = t.y0; by < t.y1; by += 4)
    for (int bx = t.x0; bx < t.x1; bx += 4) {
      pinholeRays(bx, by, packet.ray, valid);
      clearHits<16>(packet);
      observePacket(16, valid, rayLanes<16>(packet));
      rtcIntersect16(valid, scene.handle(), &ctx, &packet);
      if (hits) *hits += packetHits(packet, valid);
    }
}

void BaselineTracer::traceTileStored(const Scene& scene, const Tile& t, RTCIntersectContext& ctx,
                                     uint64_t* hits) const {
  alignas(64) RTCRayHit16 packet;
  const size_t packets = size_t((t.x1 - t.x0 + 3) / 4) * size_t((t.y1 - t.y0 + 3) / 4);
  for (size_t p = t.firstPacket; p < t.firstPacket + packets; ++p) {
    packet.ray = rays16_[p];
    clearHits<16>(packet);
    observePacket(16, valid_[p].lanes, rayLanes<16>(packet));
    rtcIntersect16(valid_[p].lanes, scene.handle(), &ctx, &packet);
    if (hits) *hits += packetHits(packet, valid_[p].lanes);
  }
}

void BaselineTracer::blockRays(int x0, int y0, size_t p, RTCRay16& rays, int* valid) const {
  if (pinhole_) return pinholeRays(x0, y0, rays, valid);
  rays = rays16_[p];
  std::copy_n(valid_[p].lanes, 16, valid);
}

void BaselineTracer::traceTileStream(const Scene& scene, const Tile& t, RTCIntersectContext& ctx,
                                     uint64_t* hits) const {
  // Thread-local buffers: one tile's packets (or rays), reused across tiles.
  thread_local std::vector<RTCRayHit16> packets;
  thread_local std::vector<RTCRayHit> single;
  packets.clear();
  single.clear();
  alignas(64) int valid[16];
  size_t p = t.firstPacket;
  for (int by = t.y0; by < t.y1; by += 4)
    for (int bx = t.x0; bx < t.x1; bx += 4, ++p) {
      packets.emplace_back();
      RTCRayHit16& packet = packets.back();
      blockRays(bx, by, p, packet.ray, valid);
      clearHits<16>(packet);
      // A stream has no lane mask: lanes outside the image get an empty interval.
      for (int k = 0; k < 16; ++k)
        if (!valid[k]) packet.ray.tnear[k] = 1.0f, packet.ray.tfar[k] = 0.0f;
      if (api_ != BaselineApi::Stream1M) continue;
      for (int k = 0; k < 16; ++k) {
        if (!valid[k]) continue;
        RTCRayHit r{};
        const RTCRay16& q = packet.ray;
        r.ray = {q.org_x[k], q.org_y[k], q.org_z[k], q.tnear[k], q.dir_x[k], q.dir_y[k],
                 q.dir_z[k], q.time[k],  q.tfar[k],  q.mask[k],  q.id[k],    q.flags[k]};
        r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        single.push_back(r);
      }
    }
  if (api_ == BaselineApi::StreamNM)
    rtcIntersectNM(scene.handle(), &ctx, reinterpret_cast<RTCRayHitN*>(packets.data()), 16,
                   unsigned(packets.size()), sizeof(RTCRayHit16));
  else
    rtcIntersect1M(scene.handle(), &ctx, single.data(), unsigned(single.size()), sizeof(RTCRayHit));
  if (!hits) return;
  // Masked-off lanes kept clearHits' invalid geomID (their interval is empty).
  if (api_ == BaselineApi::StreamNM)
    for (const RTCRayHit16& packet : packets)
      for (unsigned id : packet.hit.geomID) *hits += id != RTC_INVALID_GEOMETRY_ID;
  for (const RTCRayHit& r : single) *hits += r.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

void BaselineTracer::traceTiles(const Scene& scene, uint64_t* hits) const {
  std::atomic<uint64_t> total{0};
  parallelFor(tiles_.size(), 1, [&](size_t first, size_t last) {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    uint64_t count = 0;
    uint64_t* counter = hits ? &count : nullptr;
    for (size_t t = first; t != last; ++t) {
      if (api_ != BaselineApi::Packet16)
        traceTileStream(scene, tiles_[t], ctx, counter);
      else if (pinhole_)
        traceTilePinhole(scene, tiles_[t], ctx, counter);
      else
        traceTileStored(scene, tiles_[t], ctx, counter);
    }
    total += count;
  });
  if (hits) *hits = total;
}

double BaselineTracer::traceFrame(const Scene& scene) const {
  const auto start = std::chrono::steady_clock::now();
  traceTiles(scene, nullptr);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

uint64_t BaselineTracer::countHits(const Scene& scene) const {
  uint64_t hits = 0;
  traceTiles(scene, &hits);
  return hits;
}

}  // namespace aperture
