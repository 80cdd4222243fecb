#include "core/render.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <memory>
#include <mutex>

#include "core/error.h"
#include "core/packet.h"
#include "core/parallel.h"
#include "core/spelling.h"

namespace aperture {

NormalFrame parseNormalFrame(const std::string& name) {
  for (NormalFrame f : {NormalFrame::World, NormalFrame::OpenCV, NormalFrame::OpenGL})
    if (name == normalFrameName(f)) return f;
  throw Error(cat("unknown normal frame '", name, "'",
                  didYouMean(name, {"world", "opencv", "opengl"}),
                  " (known: world, opencv, opengl)"));
}

const char* normalFrameName(NormalFrame frame) {
  switch (frame) {
    case NormalFrame::OpenCV:
      return "opencv";
    case NormalFrame::OpenGL:
      return "opengl";
    default:
      return "world";
  }
}

void validateRenderSettings(const RenderSettings& s) {
  if (s.packetWidth != 1 && s.packetWidth != 4 && s.packetWidth != 8 && s.packetWidth != 16)
    throw Error(cat("packet width ", s.packetWidth, " is not one of 1, 4, 8, 16"));
  if (s.tileSize < 4 || s.tileSize > 4096 || s.tileSize % 4 != 0)
    throw Error(cat("tile size ", s.tileSize, " must be a multiple of 4 in [4, 4096]"));
}

namespace {

/// What one frame computes, decided once from the framebuffer's AOVs.
struct ImagePlan {
  ImagePlan(const Scene& scene, const Camera& camera, const RenderSettings& settings,
            Framebuffer& fb);

  const Scene& scene;
  const Camera& camera;
  Framebuffer& fb;
  RenderSettings settings;
  glm::vec3 eye, axis;  // render space
  glm::dvec3 origin;    // world position of the render-space origin
  bool color, depth, distance, normal, position, primId, geomId;
  bool anyGeometry;   // any AOV filled from the centre ray
  bool instanced;     // normals of instanced hits need the instance's normal matrix
  bool remapPrimIds;  // the scene was culled: primID goes through Scene::originalPrimId
  // The passes over each block: colour averages samples [0, colorSamples); the geometry AOVs
  // come from the centre ray, which at spp 1 is sample 0 itself (geometryFromSample) and
  // otherwise one extra ray per pixel, traced in pass colorSamples (the last of `passes`).
  int colorSamples;
  bool geometryFromSample;
  int passes;
};

ImagePlan::ImagePlan(const Scene& scene_, const Camera& camera_, const RenderSettings& settings_,
                     Framebuffer& fb_)
    : scene(scene_),
      camera(camera_),
      fb(fb_),
      settings(settings_),
      eye(camera_.renderEye()),
      axis(camera_.viewAxis()),
      origin(scene_.renderOrigin()),
      color(fb_.has(kAovColor)),
      depth(fb_.has(kAovDepth)),
      distance(fb_.has(kAovDistance)),
      normal(fb_.has(kAovNormal)),
      position(fb_.has(kAovPosition)),
      primId(fb_.has(kAovPrimId)),
      geomId(fb_.has(kAovGeomId)),
      anyGeometry(depth || distance || normal || position || primId || geomId),
      instanced(scene_.instanceCount() > 0),
      remapPrimIds(scene_.remapsPrimIds()),
      colorSamples(color ? settings_.spp : 0),
      geometryFromSample(anyGeometry && color && settings_.spp == 1),
      passes(colorSamples + (anyGeometry && !geometryFromSample ? 1 : 0)) {}

struct TileCounters {
  uint64_t traced = 0, skipped = 0, hits = 0;
};

/// One thread's Embree packet, its lane mask and the SoA views into it.
template <int N>
struct PacketState {
  alignas(64) typename PacketOf<N>::type packet;
  alignas(64) int valid[N];
  RayLanes lanes;
  HitLanes hits;
  RTCIntersectContext ctx;

  PacketState() : lanes(rayLanes<N>(packet)), hits(hitLanes<N>(packet)) {
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  }
  PacketState(const PacketState&) = delete;
  PacketState& operator=(const PacketState&) = delete;
};

/// Per-lane results of one traced packet: which lanes hit, and their unit normals.
template <int N>
struct PacketHits {
  alignas(64) float nx[N] = {}, ny[N] = {}, nz[N] = {};
  alignas(64) int hit[N];
  int count = 0;
};

/// Colour sums of one block over its samples.
template <int N>
struct BlockColor {
  float shade[N] = {}, cover[N] = {};
};

inline bool finiteLane(const RayLanes& l, int k) {
  return std::isfinite(l.orgX[k]) && std::isfinite(l.orgY[k]) && std::isfinite(l.orgZ[k]) &&
         std::isfinite(l.dirX[k]) && std::isfinite(l.dirY[k]) && std::isfinite(l.dirZ[k]);
}

/// Keeps the lanes to trace in Embree's −1/0 mask: the camera gave a ray, the lane lies in
/// the image and the ray is finite. Counts the skipped non-finite rays; returns the active
/// lane count.
template <int N>
int selectLanes(const ImagePlan& plan, const PacketRequest& req, PacketState<N>& st,
                TileCounters& count) {
  constexpr int kBW = blockWidthFor(N);
  // Locals: the stores to valid[] could otherwise alias them and force reloads every lane.
  const int x0 = req.x0, y0 = req.y0, width = plan.fb.width, height = plan.fb.height;
  int active = 0, nonFinite = 0;
  for (int k = 0; k < N; ++k) {
    const bool inside = laneInImage(x0, y0, kBW, k, width, height);
    const bool live = st.valid[k] != 0 && inside;
    const bool finite = finiteLane(st.lanes, k);
    nonFinite += live && !finite;
    st.valid[k] = live && finite ? -1 : 0;
    active += live && finite;
  }
  count.skipped += uint64_t(nonFinite);
  return active;
}

/// Generates and intersects the packet of `req`; false when no lane was traced.
template <int N>
bool tracePacket(const ImagePlan& plan, const PacketRequest& req, PacketState<N>& st,
                 TileCounters& count) {
  plan.camera.generate(req, st.lanes, st.valid);
  const int active = selectLanes<N>(plan, req, st, count);
  if (active == 0) return false;
  clearHits<N>(st.packet);
  intersect<N>(plan.scene.handle(), &st.ctx, st.valid, st.packet);
  count.traced += uint64_t(active);
  return true;
}

/// Marks the traced lanes that hit; returns their number.
template <int N>
int findHits(const PacketState<N>& st, PacketHits<N>& out) {
  int count = 0;
  for (int k = 0; k < N; ++k) {
    out.hit[k] = st.valid[k] != 0 && st.hits.geomID[k] != RTC_INVALID_GEOMETRY_ID;
    count += out.hit[k];
  }
  out.count = count;
  return count;
}

/// Unit geometric normals in world space (instanced hits through the instance's normal
/// matrix); 0 where Embree's normal has zero length.
template <int N>
void unitNormals(const ImagePlan& plan, const PacketState<N>& st, PacketHits<N>& out) {
  const HitLanes& h = st.hits;
  for (int k = 0; k < N; ++k) out.nx[k] = h.ngX[k], out.ny[k] = h.ngY[k], out.nz[k] = h.ngZ[k];
  if (plan.instanced)
    for (int k = 0; k < N; ++k)
      if (out.hit[k] && h.instID[k] != RTC_INVALID_GEOMETRY_ID) {
        const glm::vec3 n =
            plan.scene.normalFromMesh(h.instID[k]) * glm::vec3(out.nx[k], out.ny[k], out.nz[k]);
        out.nx[k] = n.x, out.ny[k] = n.y, out.nz[k] = n.z;
      }
  for (int k = 0; k < N; ++k) {
    const float len2 = out.nx[k] * out.nx[k] + out.ny[k] * out.ny[k] + out.nz[k] * out.nz[k];
    const float inv = len2 > 0.0f ? 1.0f / std::sqrt(len2) : 0.0f;
    out.nx[k] *= inv, out.ny[k] *= inv, out.nz[k] *= inv;
  }
}

/// Adds the eye-light shading |N·D| and the coverage of the hit lanes to the block's sums.
template <int N>
void accumulateColor(const PacketState<N>& st, const PacketHits<N>& h, BlockColor<N>& color) {
  const RayLanes& l = st.lanes;
  for (int k = 0; k < N; ++k) {
    const float c = std::fabs(h.nx[k] * l.dirX[k] + h.ny[k] * l.dirY[k] + h.nz[k] * l.dirZ[k]);
    color.shade[k] += h.hit[k] ? c : 0.0f;
    color.cover[k] += h.hit[k] ? 1.0f : 0.0f;
  }
}

/// Planar depth of every lane: (org − eye)·axis + t·(dir·axis).
template <int N>
void planarDepths(const ImagePlan& plan, const PacketState<N>& st, float* z) {
  const RayLanes& l = st.lanes;
  const glm::vec3 e = plan.eye, a = plan.axis;
  for (int k = 0; k < N; ++k)
    z[k] = (l.orgX[k] - e.x) * a.x + (l.orgY[k] - e.y) * a.y + (l.orgZ[k] - e.z) * a.z +
           st.hits.tfar[k] * (l.dirX[k] * a.x + l.dirY[k] * a.y + l.dirZ[k] * a.z);
}

/// The object of a hit: the instance, or the geometry when the mesh is attached directly.
inline unsigned objectId(const HitLanes& h, int k) {
  return h.instID[k] == RTC_INVALID_GEOMETRY_ID ? h.geomID[k] : h.instID[k];
}

/// Stores the geometry AOVs of hit lane k at framebuffer pixel px (z: the planar depths,
/// read only when depth is requested).
template <int N>
void storeGeometryLane(const ImagePlan& plan, const PacketState<N>& st, const PacketHits<N>& h,
                       int k, const float* z, size_t px) {
  Framebuffer& fb = plan.fb;
  const RayLanes& l = st.lanes;
  const float t = st.hits.tfar[k];
  if (plan.depth) fb.depth[px] = z[k];
  if (plan.distance) fb.distance[px] = t;
  if (plan.normal) {
    fb.normal[3 * px] = h.nx[k];
    fb.normal[3 * px + 1] = h.ny[k];
    fb.normal[3 * px + 2] = h.nz[k];
  }
  if (plan.position) {
    // Hit point in double: render-space origin + org + t·dir, then rounded once.
    const glm::dvec3 p = plan.origin + glm::dvec3(l.orgX[k], l.orgY[k], l.orgZ[k]) +
                         double(t) * glm::dvec3(l.dirX[k], l.dirY[k], l.dirZ[k]);
    fb.position[3 * px] = float(p.x);
    fb.position[3 * px + 1] = float(p.y);
    fb.position[3 * px + 2] = float(p.z);
  }
  if (plan.primId)
    fb.primId[px] = plan.remapPrimIds
                        ? plan.scene.originalPrimId(objectId(st.hits, k), st.hits.primID[k])
                        : st.hits.primID[k];
  if (plan.geomId) fb.geomId[px] = objectId(st.hits, k);
}

/// Stores the geometry AOVs of every hit lane of the packet of `req` (misses keep the
/// framebuffer's miss values).
template <int N>
void storeGeometry(const ImagePlan& plan, const PacketRequest& req, const PacketState<N>& st,
                   const PacketHits<N>& h) {
  constexpr int kBW = blockWidthFor(N);
  alignas(64) float z[N];
  if (plan.depth) planarDepths<N>(plan, st, z);
  const int x0 = req.x0, y0 = req.y0, width = plan.fb.width;  // not reloaded after stores
  for (int k = 0; k < N; ++k) {
    if (!h.hit[k]) continue;
    const LanePixel p = lanePixel(x0, y0, kBW, k);
    const size_t px = size_t(p.row) * size_t(width) + size_t(p.column);
    storeGeometryLane<N>(plan, st, h, k, z, px);
  }
}

/// Traces the packet of `req`; adds its shading to `color` when given, and stores the
/// geometry AOVs when `geometry` is set.
template <int N>
void renderPass(const ImagePlan& plan, const PacketRequest& req, PacketState<N>& st,
                BlockColor<N>* color, bool geometry, TileCounters& count) {
  if (!tracePacket<N>(plan, req, st, count)) return;
  PacketHits<N> hits;
  if (findHits<N>(st, hits) == 0) return;
  count.hits += uint64_t(hits.count);
  if (color || (geometry && plan.normal)) unitNormals<N>(plan, st, hits);
  if (color) accumulateColor<N>(st, hits, *color);
  if (geometry) storeGeometry<N>(plan, req, st, hits);
}

/// Writes the block's colour: the mean of its samples (R = G = B = shade, A = coverage).
template <int N>
void storeColor(const ImagePlan& plan, int bx, int by, const BlockColor<N>& color) {
  constexpr int kBW = blockWidthFor(N);
  const int width = plan.fb.width, height = plan.fb.height;
  float* const out = plan.fb.rgba.data();
  const float inv = 1.0f / float(plan.colorSamples);
  for (int k = 0; k < N; ++k) {
    if (!laneInImage(bx, by, kBW, k, width, height)) continue;
    const LanePixel p = lanePixel(bx, by, kBW, k);
    float* rgba = out + 4 * (size_t(p.row) * size_t(width) + size_t(p.column));
    const float c = color.shade[k] * inv;
    rgba[0] = rgba[1] = rgba[2] = c;
    rgba[3] = color.cover[k] * inv;
  }
}

/// Renders the block of N pixels whose top-left pixel is (row by, column bx): the colour
/// samples, then the centre ray when it is a pass of its own. One call site of renderPass,
/// so the compiler inlines the whole pass into the block loop.
template <int N>
void renderBlock(const ImagePlan& plan, int bx, int by, PacketState<N>& st, TileCounters& count) {
  constexpr int kBW = blockWidthFor(N), kBH = blockHeightFor(N);
  BlockColor<N> color;
  for (int pass = 0; pass < plan.passes; ++pass) {
    const bool centre = pass == plan.colorSamples;
    const PacketRequest req{bx, by, kBW, kBH, centre ? PacketRequest::kCentreRay : pass};
    renderPass<N>(plan, req, st, centre ? nullptr : &color, centre || plan.geometryFromSample,
                  count);
  }
  if (plan.color) storeColor<N>(plan, bx, by, color);
}

/// Renders the tile of columns [x0, x1) and rows [y0, y1), block by block.
template <int N>
void renderTile(const ImagePlan& plan, int x0, int y0, int x1, int y1, TileCounters& count) {
  // Denormals flushed on every worker (Embree's recommendation); same mode on all threads.
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  PacketState<N> st;
  for (int by = y0; by < y1; by += blockHeightFor(N))
    for (int bx = x0; bx < x1; bx += blockWidthFor(N)) renderBlock<N>(plan, bx, by, st, count);
}

/// renderTile for the plan's packet width.
void renderTileOfWidth(const ImagePlan& plan, int x0, int y0, int x1, int y1, TileCounters& count) {
  switch (plan.settings.packetWidth) {
    case 1:
      return renderTile<1>(plan, x0, y0, x1, y1, count);
    case 4:
      return renderTile<4>(plan, x0, y0, x1, y1, count);
    case 8:
      return renderTile<8>(plan, x0, y0, x1, y1, count);
    default:
      return renderTile<16>(plan, x0, y0, x1, y1, count);
  }
}

/// Throws Error when the framebuffer is empty or does not match the camera's image size
/// and spp.
void checkFramebuffer(const Camera& camera, const RenderSettings& settings, const Framebuffer& fb) {
  if (fb.width <= 0 || fb.height <= 0 || fb.aovs == 0)
    throw Error(cat("framebuffer ", fb.width, "x", fb.height, " with AOVs '",
                    aovListString(fb.aovs), "' is empty"));
  const CameraDescription desc = camera.describe();
  if (desc.width != fb.width || desc.height != fb.height || desc.spp != settings.spp)
    throw Error(cat("camera image ", desc.width, "x", desc.height, " spp ", desc.spp,
                    " does not match the framebuffer ", fb.width, "x", fb.height, " spp ",
                    settings.spp));
}

}  // namespace

RenderStats renderImage(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                        Framebuffer& fb) {
  validateRenderSettings(settings);
  checkFramebuffer(camera, settings, fb);
  const ImagePlan plan(scene, camera, settings, fb);
  const int ts = settings.tileSize;
  const int tilesX = (fb.width + ts - 1) / ts, tilesY = (fb.height + ts - 1) / ts;
  std::atomic<uint64_t> traced{0}, skipped{0}, hits{0};
  const auto start = std::chrono::steady_clock::now();
  parallelFor(size_t(tilesX) * size_t(tilesY), 1, [&](size_t first, size_t last) {
    for (int tile = int(first); tile != int(last); ++tile) {
      const int x0 = (tile % tilesX) * ts, y0 = (tile / tilesX) * ts;
      const int x1 = std::min(x0 + ts, fb.width), y1 = std::min(y0 + ts, fb.height);
      TileCounters c;
      renderTileOfWidth(plan, x0, y0, x1, y1, c);
      traced += c.traced;
      skipped += c.skipped;
      hits += c.hits;
    }
  });
  RenderStats stats;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.raysTraced = traced;
  stats.raysSkipped = skipped;
  stats.hits = hits;
  return stats;
}

namespace {

/// Work counters of one frame of renderImages, summed over its tiles.
struct FrameProgress {
  std::atomic<uint64_t> traced{0}, skipped{0}, hits{0};
  std::atomic<size_t> tilesLeft{0};
};

}  // namespace

std::vector<RenderStats> renderImages(const Scene& scene, const std::vector<const Camera*>& cameras,
                                      const RenderSettings& settings,
                                      std::vector<Framebuffer>& framebuffers,
                                      const std::function<void(size_t)>& progress) {
  validateRenderSettings(settings);
  if (cameras.size() != framebuffers.size())
    throw Error(cat("renderImages: ", cameras.size(), " cameras but ", framebuffers.size(),
                    " framebuffers"));
  const size_t n = cameras.size();
  const int ts = settings.tileSize;
  // One plan per frame, as renderImage makes it (with the camera's own spp), and the frames'
  // tiles numbered one after another: frame k owns tiles [firstTile[k], firstTile[k + 1]).
  std::deque<ImagePlan> plans;
  std::vector<size_t> firstTile(n + 1, 0);
  std::unique_ptr<FrameProgress[]> frames(new FrameProgress[n]);
  for (size_t k = 0; k < n; ++k) {
    APERTURE_CHECK_OP(cameras[k], !=, nullptr);
    RenderSettings forCamera = settings;
    forCamera.spp = cameras[k]->describe().spp;
    checkFramebuffer(*cameras[k], forCamera, framebuffers[k]);
    plans.emplace_back(scene, *cameras[k], forCamera, framebuffers[k]);
    const size_t tiles = size_t((framebuffers[k].width + ts - 1) / ts) *
                         size_t((framebuffers[k].height + ts - 1) / ts);
    frames[k].tilesLeft = tiles;
    firstTile[k + 1] = firstTile[k] + tiles;
  }
  std::vector<RenderStats> stats(n);
  std::mutex progressMutex;
  size_t framesDone = 0;
  const auto start = std::chrono::steady_clock::now();
  parallelFor(firstTile[n], 1, [&](size_t first, size_t last) {
    for (size_t tile = first; tile != last; ++tile) {
      const size_t k =
          size_t(std::upper_bound(firstTile.begin(), firstTile.end(), tile) - firstTile.begin()) -
          1;
      const ImagePlan& plan = plans[k];
      const int tilesX = (plan.fb.width + ts - 1) / ts, local = int(tile - firstTile[k]);
      const int x0 = (local % tilesX) * ts, y0 = (local / tilesX) * ts;
      const int x1 = std::min(x0 + ts, plan.fb.width), y1 = std::min(y0 + ts, plan.fb.height);
      TileCounters c;
      renderTileOfWidth(plan, x0, y0, x1, y1, c);
      FrameProgress& f = frames[k];
      f.traced += c.traced;
      f.skipped += c.skipped;
      f.hits += c.hits;
      if (--f.tilesLeft != 0) continue;
      // The frame's last tile: its counters are complete (every other tile decremented
      // tilesLeft after adding its counts).
      stats[k].seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      stats[k].raysTraced = f.traced;
      stats[k].raysSkipped = f.skipped;
      stats[k].hits = f.hits;
      const std::lock_guard<std::mutex> lock(progressMutex);
      ++framesDone;
      if (progress) progress(framesDone);
    }
  });
  return stats;
}

}  // namespace aperture
