#include "core/queries/visibility.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/aov/framebuffer.h"
#include "core/engine/intersect_scene.h"
#include "core/engine/packet.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace aperture {

namespace {

constexpr int kLanes = 16;  ///< rays per Embree call (rtcIntersect16 / rtcOccluded16)
/// Faces or points per parallel task: a multiple of the packet width, large enough that the
/// per-task bookkeeping (one small vector) does not matter.
constexpr size_t kItemsPerTask = 4096;
/// At most this many primID pixels alive at once while face pixels are counted (4 bytes each).
constexpr size_t kMaxPixelsAlive = size_t(64) << 20;
/// Edge in pixels of the tiles that order the rays of one camera, so rays through neighbouring
/// pixels share a packet as in the frame loop: a mesh's file order can jump across the model
/// (16 consecutive faces of the dragon spread over a quarter of its size). Measured on the
/// dragon (bench/RESULTS.md, issue 15): face rays cost the same with tiles of 2 to 16 pixels
/// or in file order (each ray ends on the surface, as a render's hit rays do, at ~9 M/s on 2
/// cores); point queries gained 7.9 -> 10.2 M/s.
constexpr int kTilePixels = 16;
/// Halvings of a triangle towards its centroid before projectedAreaPixels gives up (the
/// triangle is then 2^-30 of its size: below any pixel).
constexpr int kMaxHalvings = 30;

/// A camera with its image size, read once (describe() is not free).
struct CameraImage {
  const Camera& camera;
  double width, height;
};

CameraImage cameraImage(const Camera& camera) {
  const CameraDescription d = camera.describe();
  return {camera, double(d.width), double(d.height)};
}

/// The raster position of world point p when it lies inside the image, [0, W) x [0, H)
/// (pixel (i, j) centre at (j + ½, i + ½), so the image's outer edges are 0 and W, H).
std::optional<glm::dvec2> rasterInside(const CameraImage& image, const glm::dvec3& worldPoint) {
  const std::optional<glm::dvec2> r = image.camera.project(worldPoint);
  if (!r) return std::nullopt;
  const bool inside = r->x >= 0 && r->x < image.width && r->y >= 0 && r->y < image.height;
  return inside ? r : std::nullopt;
}

/// An item (face or point) whose world point projects inside a camera's image, and where.
struct ProjectedItem {
  uint32_t index;
  glm::dvec2 raster;
};

bool finite(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// The scene's one mesh, refused unless the scene is that mesh attached directly (one object,
/// no instance, no culling), so Embree's geomID 0 and primID are the mesh and its triangle.
const Mesh& onlyMesh(const Scene& scene, const char* what) {
  if (scene.objectCount() != 1)
    throw Error(cat(what, ": the scene holds ", scene.objectCount(),
                    " objects; visibility is defined over exactly one mesh"));
  if (scene.instanceCount() != 0)
    throw Error(cat(what,
                    ": the mesh is placed by an Embree instance (transformed or "
                    "repeated); visibility needs it untransformed and placed once"));
  if (scene.culled())
    throw Error(cat(what,
                    ": the scene was culled to a subset of triangles; visibility needs "
                    "every triangle of the mesh"));
  return scene.objectMesh(0);
}

/// The three corners of triangle f in world space, in double: anchor + positions.
struct Triangle {
  glm::dvec3 a, b, c;
  glm::dvec3 centroid() const { return (a + b + c) / 3.0; }
  /// The normal of the counter-clockwise winding, (b − a) × (c − a), not normalised.
  glm::dvec3 windingNormal() const { return glm::cross(b - a, c - a); }
};

Triangle worldTriangle(const Mesh& mesh, size_t f) {
  auto corner = [&](int k) {
    return mesh.anchor + glm::dvec3(mesh.vertex(mesh.indices[3 * f + size_t(k)]));
  };
  return {corner(0), corner(1), corner(2)};
}

// ---------------------------------------------------------------------------------------------
// Sparse rows

/// Appends one row (ascending indices) to `rows`.
void appendRow(SparseRows& rows, const std::vector<uint32_t>& row) {
  rows.indices.insert(rows.indices.end(), row.begin(), row.end());
  rows.indptr.push_back(rows.indices.size());
}

/// The per-task lists of one camera, in task order: ascending, since tasks cover consecutive
/// ranges of faces or points.
std::vector<uint32_t> concatenate(const std::vector<std::vector<uint32_t>>& perTask) {
  std::vector<uint32_t> all;
  size_t total = 0;
  for (const auto& part : perTask) total += part.size();
  all.reserve(total);
  for (const auto& part : perTask) all.insert(all.end(), part.begin(), part.end());
  return all;
}

size_t taskCount(size_t items) { return (items + kItemsPerTask - 1) / kItemsPerTask; }

/// Calls body(task, begin, end) in parallel for the numbered tasks of kItemsPerTask items
/// (parallelForChunks), so each task owns slot `task` of a per-task array.
template <class Body>
void forEachTask(size_t items, const Body& body) {
  parallelForChunks(items, kItemsPerTask, body);
}

// ---------------------------------------------------------------------------------------------
// Packet lanes (faces and points)

/// Writes lane k of a packet: a render-space ray, tnear 0 and the given tfar.
void setLane(RayLanes& l, int k, const glm::dvec3& org, const glm::dvec3& dir, float tfar) {
  l.orgX[k] = float(org.x), l.orgY[k] = float(org.y), l.orgZ[k] = float(org.z);
  l.dirX[k] = float(dir.x), l.dirY[k] = float(dir.y), l.dirZ[k] = float(dir.z);
  l.tnear[k] = 0.0f, l.tfar[k] = tfar, l.time[k] = 0.0f;
  l.mask[k] = 0xFFFFFFFFu, l.id[k] = unsigned(k), l.flags[k] = 0;
}

/// A lane with no ray: finite values, masked off by valid[k] = 0.
void setIdleLane(RayLanes& l, int k) { setLane(l, k, glm::dvec3(0.0), glm::dvec3(0, 0, 1), 0.0f); }

// ---------------------------------------------------------------------------------------------
// Projection in tile order (faces and points)

/// The items (faces or points) whose world point projects inside `image`, with their raster
/// positions, ordered by the kTilePixels tile the position falls in (tiles row by row; within
/// a tile, ascending item index). Projection runs in parallel, the counting sort serially.
template <class WorldPointOf>
std::vector<ProjectedItem> projectedByTile(const CameraImage& image, size_t items,
                                           const WorldPointOf& worldPointOf) {
  std::vector<std::vector<ProjectedItem>> perTask(taskCount(items));
  forEachTask(items, [&](size_t task, size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      if (const std::optional<glm::dvec2> r = rasterInside(image, worldPointOf(i)))
        perTask[task].push_back({uint32_t(i), *r});
  });
  const size_t tilesX = (size_t(image.width) + kTilePixels - 1) / kTilePixels;
  const size_t tilesY = (size_t(image.height) + kTilePixels - 1) / kTilePixels;
  auto tileOf = [&](const ProjectedItem& p) {
    return size_t(p.raster.y) / kTilePixels * tilesX + size_t(p.raster.x) / kTilePixels;
  };
  std::vector<size_t> next(tilesX * tilesY + 1, 0);
  for (const auto& part : perTask)
    for (const ProjectedItem& p : part) ++next[tileOf(p) + 1];
  for (size_t t = 1; t < next.size(); ++t) next[t] += next[t - 1];
  std::vector<ProjectedItem> sorted(next.back());
  for (const auto& part : perTask)
    for (const ProjectedItem& p : part) sorted[next[tileOf(p)]++] = p;
  return sorted;
}

/// The ascending indices k < flags.size() with flags[k] set, in parallel.
std::vector<uint32_t> flaggedIndices(const std::vector<uint8_t>& flags) {
  std::vector<std::vector<uint32_t>> perTask(taskCount(flags.size()));
  forEachTask(flags.size(), [&](size_t task, size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k)
      if (flags[k]) perTask[task].push_back(uint32_t(k));
  });
  return concatenate(perTask);
}

// ---------------------------------------------------------------------------------------------
// Faces

/// Sets seen[f] for the faces of projected[first, last) that `image` sees (conditions 2 and 3
/// of the header; condition 1 made them projected): packets of up to 16, one centre ray each.
/// With FaceRays::needed, a lane whose ray meets the face from behind under frontOnly is left
/// idle: condition 3 fails whatever the ray hits.
void markSeenFaces(const Scene& scene, const Mesh& mesh, const CameraImage& image, bool frontOnly,
                   FaceRays rays, const ProjectedItem* projected, size_t count,
                   std::vector<uint8_t>& seen) {
  PacketBuffers<kLanes> p;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  alignas(64) double facing[kLanes];  // frontOnly: dot(direction, winding normal) per lane
  for (size_t first = 0; first < count; first += kLanes) {
    int active = 0;
    for (int k = 0; k < kLanes; ++k) {
      p.valid[k] = 0;
      facing[k] = 0;
      setIdleLane(p.lanes, k);
      if (first + size_t(k) >= count) continue;
      const ProjectedItem& item = projected[first + size_t(k)];
      glm::dvec3 org, dir;
      if (!image.camera.centreRayAt(item.raster.x, item.raster.y, org, dir)) continue;
      if (!finite(org) || !finite(dir)) continue;
      if (frontOnly) {
        facing[k] = glm::dot(dir, worldTriangle(mesh, item.index).windingNormal());
        if (rays == FaceRays::needed && !(facing[k] < 0)) continue;
      }
      setLane(p.lanes, k, org, dir, std::numeric_limits<float>::infinity());
      p.valid[k] = -1;
      ++active;
    }
    if (active == 0) continue;
    clearHits<kLanes>(p.packet);
    intersectScene<kLanes>(scene, &ctx, p.valid, p.packet);
    for (int k = 0; k < kLanes; ++k) {
      if (!p.valid[k]) continue;
      const uint32_t f = projected[first + size_t(k)].index;
      const bool hitsFace = p.hits.geomID[k] == 0 && p.hits.primID[k] == f;
      if (hitsFace && (!frontOnly || facing[k] < 0)) seen[f] = 1;
    }
  }
}

/// Every face `image` sees, ascending: centroids projected and ordered by tile, traced in
/// parallel tasks of consecutive tile-ordered faces.
std::vector<uint32_t> seenFaces(const Scene& scene, const Mesh& mesh, const CameraImage& image,
                                bool frontOnly, FaceRays rays) {
  const std::vector<ProjectedItem> projected = projectedByTile(
      image, mesh.triangleCount(), [&](size_t f) { return worldTriangle(mesh, f).centroid(); });
  std::vector<uint8_t> seen(mesh.triangleCount(), 0);
  forEachTask(projected.size(), [&](size_t, size_t begin, size_t end) {
    markSeenFaces(scene, mesh, image, frontOnly, rays, projected.data() + begin, end - begin, seen);
  });
  return flaggedIndices(seen);
}

/// Groups of consecutive cameras whose primID images together hold at most kMaxPixelsAlive
/// pixels (a larger camera alone forms a group): [starts[g], starts[g + 1]).
std::vector<size_t> cameraGroupStarts(const std::vector<CameraImage>& images) {
  std::vector<size_t> starts{0};
  size_t pixels = 0;
  for (size_t c = 0; c < images.size(); ++c) {
    const size_t n = size_t(images[c].width) * size_t(images[c].height);
    if (pixels > 0 && pixels + n > kMaxPixelsAlive) {
      starts.push_back(c);
      pixels = 0;
    }
    pixels += n;
  }
  if (starts.back() != images.size()) starts.push_back(images.size());
  return starts;
}

/// Adds the primID images of cameras [first, last) to `pixels`: the frame loop's own renders
/// (centre rays, each camera's spp), bincounted, so face pixels equal the renders by
/// construction.
void countFacePixels(const Scene& scene, const std::vector<const Camera*>& cameras,
                     const std::vector<CameraImage>& images, size_t first, size_t last,
                     const RenderSettings& settings, std::vector<uint64_t>& pixels) {
  const std::vector<const Camera*> group(cameras.begin() + long(first),
                                         cameras.begin() + long(last));
  std::vector<Framebuffer> framebuffers;
  framebuffers.reserve(group.size());
  for (size_t c = first; c < last; ++c)
    framebuffers.emplace_back(int(images[c].width), int(images[c].height), AovSet(kAovPrimId));
  renderImages(scene, group, settings, framebuffers);
  for (const Framebuffer& fb : framebuffers)
    for (uint32_t prim : fb.primId)
      if (prim != kInvalidId) ++pixels[prim];
}

void checkFaceOptions(const FaceVisibilityOptions& options) {
  validateRenderSettings(options.render);
  if (options.render.nullTrace)
    throw Error(
        "faceVisibility: the null trace (bench --null) fakes hits; face pixels need "
        "the real primID renders");
}

/// Counts camera `c`'s seen faces into the per-face results and keeps, per face, the camera
/// with the largest projected area so far (strict >, so the lower camera index keeps a tie).
void recordSeenFaces(const Mesh& mesh, const Camera& camera, uint32_t c,
                     const std::vector<uint32_t>& seen, FaceVisibility& out,
                     std::vector<double>& bestArea) {
  parallelFor(seen.size(), kItemsPerTask / 4, [&](size_t begin, size_t end) {
    for (size_t s = begin; s < end; ++s) {
      const uint32_t f = seen[s];
      ++out.viewCount[f];
      const Triangle t = worldTriangle(mesh, f);
      const double area = projectedAreaPixels(camera, t.a, t.b, t.c);
      if (out.bestView[f] < 0 || area > bestArea[f]) {
        bestArea[f] = area;
        out.bestView[f] = int32_t(c);
      }
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Points

void checkTolerance(double tolerance, const char* what) {
  if (!(tolerance >= 0 && tolerance < 1))
    throw Error(cat(what, ": occlusion tolerance ", tolerance, " is outside [0, 1)"));
}

void checkPoints(const std::vector<glm::dvec3>& points, const char* what) {
  for (size_t k = 0; k < points.size(); ++k)
    if (!finite(points[k]))
      throw Error(cat(what, ": point ", k, " is not finite (", points[k].x, ", ", points[k].y, ", ",
                      points[k].z, ")"));
}

/// An RTCRay16 with its lane mask, aligned as rtcOccluded16 requires.
struct OcclusionPacket {
  alignas(64) RTCRay16 ray;
  alignas(64) int valid[kLanes];
};

/// The one decision of point visibility (pointVisibility and classifyObservations both call
/// it) for points that project inside `image` (rasterInside): occluded[k] for each of
/// projected[0 .. n), n <= 16, whose world points are points[projected[k].index]. The occlusion
/// ray runs from the centre-ray origin o at the point's raster position towards p (render
/// space, direction (p − o) / d rounded once) over [0, d·(1 − tolerance)]; a point at the
/// origin (d = 0) is not occluded.
void markOccluded(const Scene& scene, const CameraImage& image,
                  const std::vector<glm::dvec3>& points, const ProjectedItem* projected, int n,
                  double tolerance, bool* occluded) {
  OcclusionPacket p;
  RayLanes l{};
  l.width = kLanes;
  l.orgX = p.ray.org_x, l.orgY = p.ray.org_y, l.orgZ = p.ray.org_z, l.tnear = p.ray.tnear;
  l.dirX = p.ray.dir_x, l.dirY = p.ray.dir_y, l.dirZ = p.ray.dir_z, l.time = p.ray.time;
  l.tfar = p.ray.tfar, l.mask = p.ray.mask, l.id = p.ray.id, l.flags = p.ray.flags;
  for (int k = 0; k < kLanes; ++k) {
    p.valid[k] = 0;
    setIdleLane(l, k);
    if (k >= n) continue;
    occluded[k] = false;
    glm::dvec3 org, unused;
    const glm::dvec2 r = projected[k].raster;
    if (!image.camera.centreRayAt(r.x, r.y, org, unused) || !finite(org)) continue;
    const glm::dvec3 towards = (points[projected[k].index] - scene.renderOrigin()) - org;
    const double d = glm::length(towards);
    if (!(d > 0)) continue;
    setLane(l, k, org, towards / d, float(d * (1.0 - tolerance)));
    p.valid[k] = -1;
  }
  if (sealLanes<kLanes>(p.valid, l) == 0) return;
  observePacket(kLanes, p.valid, l);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcOccluded16(p.valid, scene.handle(), &ctx, &p.ray);
  // Embree marks an occluded ray by setting its tfar to −inf.
  for (int k = 0; k < n; ++k)
    occluded[k] = p.valid[k] && p.ray.tfar[k] == -std::numeric_limits<float>::infinity();
}

/// Every point `image` sees, ascending: points projected and ordered by tile, their
/// occlusion rays traced in parallel tasks of consecutive tile-ordered points.
std::vector<uint32_t> seenPoints(const Scene& scene, const CameraImage& image,
                                 const std::vector<glm::dvec3>& points, double tolerance) {
  const std::vector<ProjectedItem> projected =
      projectedByTile(image, points.size(), [&](size_t k) { return points[k]; });
  std::vector<uint8_t> seen(points.size(), 0);
  forEachTask(projected.size(), [&](size_t, size_t begin, size_t end) {
    bool occluded[kLanes];
    for (size_t first = begin; first < end; first += kLanes) {
      const int n = int(std::min<size_t>(kLanes, end - first));
      markOccluded(scene, image, points, &projected[first], n, tolerance, occluded);
      for (int k = 0; k < n; ++k)
        if (!occluded[k]) seen[projected[first + size_t(k)].index] = 1;
    }
  });
  return flaggedIndices(seen);
}

/// The observations of each camera: row c lists the indices into `observations` whose camera
/// is c (checked against the numbers of cameras and points).
SparseRows observationsByCamera(const std::vector<PointObservation>& observations, size_t cameras,
                                size_t points) {
  SparseRows obs;
  for (size_t k = 0; k < observations.size(); ++k) {
    const PointObservation& o = observations[k];
    if (o.camera >= cameras || o.point >= points)
      throw Error(cat("classifyObservations: observation ", k, " (point ", o.point, ", camera ",
                      o.camera, ") is out of range: ", points, " points, ", cameras, " cameras"));
    obs.indices.push_back(o.camera);
    obs.indptr.push_back(k + 1);
  }
  // One row per observation holding its camera; transposed, one row per camera holding its
  // observations.
  return transposeRows(obs, cameras);
}

/// Counts how `image` sees the observations observations[rows[0 .. count)] (all of its camera):
/// outside where the point does not project inside the image, else occluded or seen by
/// markOccluded, in packets of up to 16.
ObservationCounts countObservations(const Scene& scene, const CameraImage& image,
                                    const std::vector<glm::dvec3>& points,
                                    const std::vector<PointObservation>& observations,
                                    const uint32_t* rows, size_t count, double tolerance) {
  ObservationCounts counts;
  ProjectedItem inside[kLanes];
  bool occluded[kLanes];
  int n = 0;
  auto flush = [&] {
    markOccluded(scene, image, points, inside, n, tolerance, occluded);
    for (int k = 0; k < n; ++k) occluded[k] ? ++counts.occluded : ++counts.seen;
    n = 0;
  };
  for (size_t k = 0; k < count; ++k) {
    const uint32_t point = observations[rows[k]].point;
    const std::optional<glm::dvec2> r = rasterInside(image, points[point]);
    if (!r) {
      ++counts.outside;
      continue;
    }
    inside[n++] = {point, *r};
    if (n == kLanes) flush();
  }
  if (n > 0) flush();
  return counts;
}

}  // namespace

SparseRows transposeRows(const SparseRows& rows, size_t columns) {
  SparseRows t;
  t.indptr.assign(columns + 1, 0);
  for (size_t k = 0; k < rows.indices.size(); ++k) {
    const uint32_t c = rows.indices[k];
    if (c >= columns)
      throw Error(cat("transposeRows: index ", c, " at position ", k, " is not below the ", columns,
                      " columns"));
    ++t.indptr[c + 1];
  }
  for (size_t c = 0; c < columns; ++c) t.indptr[c + 1] += t.indptr[c];
  t.indices.resize(rows.indices.size());
  std::vector<uint64_t> next(t.indptr.begin(), t.indptr.end() - 1);
  // Rows in order: each column's list receives its rows ascending.
  for (size_t r = 0; r < rows.rows(); ++r)
    for (uint64_t k = rows.indptr[r]; k < rows.indptr[r + 1]; ++k)
      t.indices[next[rows.indices[k]]++] = uint32_t(r);
  return t;
}

/// The per-face results counted over the stored triangles (viewCount, bestView, cameraFaces)
/// put in the loaded order, which faces are reported in, for a mesh whose triangles
/// orderTrianglesInSpace moved. `pixels`, bincounted from primID renders, is in it already.
void putInLoadedOrder(const Mesh& mesh, FaceVisibility& out) {
  if (mesh.sourceTriangles.empty()) return;
  const std::vector<uint32_t>& source = mesh.sourceTriangles;
  std::vector<uint32_t> viewCount(out.viewCount.size());
  std::vector<int32_t> bestView(out.bestView.size());
  for (size_t t = 0; t < source.size(); ++t) {
    viewCount[source[t]] = out.viewCount[t];
    bestView[source[t]] = out.bestView[t];
  }
  out.viewCount.swap(viewCount);
  out.bestView.swap(bestView);
  SparseRows& rows = out.cameraFaces;
  for (size_t r = 0; r < rows.rows(); ++r) {
    const auto begin = rows.indices.begin() + std::ptrdiff_t(rows.indptr[r]);
    const auto end = rows.indices.begin() + std::ptrdiff_t(rows.indptr[r + 1]);
    for (auto f = begin; f != end; ++f) *f = source[*f];
    std::sort(begin, end);
  }
}

FaceVisibility faceVisibility(const Scene& scene, const std::vector<const Camera*>& cameras,
                              const FaceVisibilityOptions& options) {
  const Mesh& mesh = onlyMesh(scene, "faceVisibility");
  checkFaceOptions(options);
  const size_t faces = mesh.triangleCount();
  std::vector<CameraImage> images;
  images.reserve(cameras.size());
  for (const Camera* camera : cameras) images.push_back(cameraImage(*camera));

  FaceVisibility out;
  out.viewCount.assign(faces, 0);
  out.pixels.assign(faces, 0);
  out.bestView.assign(faces, -1);
  std::vector<double> bestArea(faces, 0.0);
  const std::vector<size_t> starts = cameraGroupStarts(images);
  for (size_t g = 0; g + 1 < starts.size(); ++g) {
    countFacePixels(scene, cameras, images, starts[g], starts[g + 1], options.render, out.pixels);
    for (size_t c = starts[g]; c < starts[g + 1]; ++c) {
      const std::vector<uint32_t> seen =
          seenFaces(scene, mesh, images[c], options.frontOnly, options.rays);
      recordSeenFaces(mesh, *cameras[c], uint32_t(c), seen, out, bestArea);
      appendRow(out.cameraFaces, seen);
      if (options.progress) options.progress(c + 1, cameras.size());
    }
  }
  putInLoadedOrder(mesh, out);
  out.faceCameras = transposeRows(out.cameraFaces, faces);
  return out;
}

double projectedAreaPixels(const Camera& camera, const glm::dvec3& a, const glm::dvec3& b,
                           const glm::dvec3& c) {
  const glm::dvec3 g = (a + b + c) / 3.0;
  double scale = 1;  // the corners' distance from g relative to the triangle's: 2^-halvings
  for (int halving = 0; halving <= kMaxHalvings; ++halving, scale *= 0.5) {
    const auto pa = camera.project(g + scale * (a - g));
    const auto pb = camera.project(g + scale * (b - g));
    const auto pc = camera.project(g + scale * (c - g));
    if (!pa || !pb || !pc) continue;
    const glm::dvec2 u = *pb - *pa, v = *pc - *pa;
    // Area scales with the square of the size: 4 per halving.
    return 0.5 * std::abs(u.x * v.y - u.y * v.x) / (scale * scale);
  }
  return 0;
}

PointVisibility pointVisibility(const Scene& scene, const std::vector<const Camera*>& cameras,
                                const std::vector<glm::dvec3>& points,
                                const PointVisibilityOptions& options) {
  onlyMesh(scene, "pointVisibility");
  checkTolerance(options.tolerance, "pointVisibility");
  checkPoints(points, "pointVisibility");
  PointVisibility out;
  for (size_t c = 0; c < cameras.size(); ++c) {
    appendRow(out.cameraPoints,
              seenPoints(scene, cameraImage(*cameras[c]), points, options.tolerance));
    if (options.progress) options.progress(c + 1, cameras.size());
  }
  out.pointCameras = transposeRows(out.cameraPoints, points.size());
  return out;
}

ObservationCounts classifyObservations(const Scene& scene,
                                       const std::vector<const Camera*>& cameras,
                                       const std::vector<glm::dvec3>& points,
                                       const std::vector<PointObservation>& observations,
                                       double tolerance) {
  onlyMesh(scene, "classifyObservations");
  checkTolerance(tolerance, "classifyObservations");
  checkPoints(points, "classifyObservations");
  const SparseRows byCamera = observationsByCamera(observations, cameras.size(), points.size());
  ObservationCounts total;
  for (size_t c = 0; c < cameras.size(); ++c) {
    const CameraImage image = cameraImage(*cameras[c]);
    const uint64_t first = byCamera.indptr[c], count = byCamera.indptr[c + 1] - first;
    std::vector<ObservationCounts> perTask(taskCount(count));
    forEachTask(count, [&](size_t task, size_t begin, size_t end) {
      perTask[task] =
          countObservations(scene, image, points, observations,
                            byCamera.indices.data() + first + begin, end - begin, tolerance);
    });
    for (const ObservationCounts& part : perTask) {
      total.seen += part.seen;
      total.occluded += part.occluded;
      total.outside += part.outside;
    }
  }
  return total;
}

}  // namespace aperture
