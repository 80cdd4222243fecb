#include "apps/services/scene_setup.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "apps/services/limits.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/culling.h"
#include "core/engine/layers.h"
#include "core/engine/triangle_order.h"
#include "core/util/error.h"

namespace aperture::app {

void checkMemoryBudget(const SceneOptions& o, glm::ivec2 size, const AovSet& aovs,
                       uint64_t extraBytesPerPixel, bool imageCodec,
                       const std::vector<CameraParams>& cameras) {
  const uint64_t limit = parseMemoryLimit("--max-memory", o.maxMemory);
  if (limit == 0) return;
  std::vector<std::string> specs = o.meshes;
  if (specs.empty()) specs.push_back("procedural:default");
  MemoryEstimate e = estimateMemory(specs, uint64_t(size.x), uint64_t(size.y), aovs,
                                    extraBytesPerPixel, o.buildOptions());
  if (imageCodec) e.imageCodecBytes = kImageCodecBytes;
  e.lensTableBytes = directionTableBytes(cameras);
  checkMemoryLimit(e, limit, "--max-memory", o.maxMemory);
}

LoadOptions SceneOptions::loadOptions() const {
  LoadOptions o;
  o.placement = worldSpace ? Placement::WorldSpace : Placement::CameraRelative;
  return o;
}

BuildOptions SceneOptions::buildOptions() const {
  BuildOptions b;
  b.quality = parseBvhQuality(quality);
  b.robust = robust;
  b.compact = compact;
  b.bvhChunkTriangles = checkedBvhChunkTriangles(bvhChunk, "--bvh-chunk");
  return b;
}

void logLoadedMesh(const Mesh& m) {
  std::fprintf(stderr, "aperture: loaded %s: %zu triangles, %zu vertices in %.3f s", m.name.c_str(),
               m.triangleCount(), m.vertexCount, m.stats.loadSeconds);
  if (m.stats.fileBytes)
    std::fprintf(stderr, " (%.1f MB/s)",
                 m.stats.fileBytes / 1e6 / std::max(m.stats.loadSeconds, 1e-9));
  std::fprintf(stderr, "\n");
  if (m.stats.nonFiniteVertices || m.stats.droppedTriangles)
    std::fprintf(stderr, "aperture: %s: %zu non-finite vertices, %zu triangles dropped\n",
                 m.name.c_str(), m.stats.nonFiniteVertices, m.stats.droppedTriangles);
}

SceneSpec SceneOptions::spec() const {
  SceneSpec s;
  for (const std::string& m : meshes) s.meshes.push_back({m, std::nullopt});
  if (s.meshes.empty()) s.meshes.push_back({"procedural:default", std::nullopt});
  s.placement = loadOptions().placement;
  s.build = buildOptions();
  s.cull = cull;
  return withAovNeeds(s, aovs);
}

SceneSpec withAovNeeds(SceneSpec spec, const AovSet& aovs) {
  spec.properties = aovs.properties;
  spec.vertexNormals = aovs.has(kAovShadingNormal);
  spec.build.contextFilter = layersNeedContextFilter(aovs);
  return spec;
}

void logCullStats(const CullStats& c, size_t cameras) {
  std::fprintf(
      stderr,
      "aperture: culled to the view volume%s of %zu camera%s: kept %zu of %zu "
      "triangles (%.2f%%) in %.3f s\n",
      cameras == 1 ? "" : "s", cameras, cameras == 1 ? "" : "s", c.trianglesKept, c.trianglesBefore,
      c.trianglesBefore ? 100.0 * double(c.trianglesKept) / double(c.trianglesBefore) : 100.0,
      c.seconds);
}

void moveAnchor(Mesh& m, const glm::dvec3& anchor) {
  const glm::dvec3 delta = m.anchor - anchor;
  for (size_t v = 0; v < m.vertexCount; ++v)
    for (int c = 0; c < 3; ++c)
      m.positions[3 * v + c] = float(double(m.positions[3 * v + c]) + delta[c]);
  m.anchor = anchor;
}

namespace {

/// How many placements use each file.
std::map<std::string, size_t> usesOf(const SceneSpec& spec) {
  std::map<std::string, size_t> uses;
  for (const MeshPlacement& m : spec.meshes) ++uses[m.spec];
  return uses;
}

/// Loads each distinct file once (transform baked in when used once).
std::map<std::string, Mesh*> loadDistinctMeshes(LoadedScene& s, const SceneSpec& spec,
                                                const std::map<std::string, size_t>& uses,
                                                bool quiet) {
  std::map<std::string, Mesh*> bySpec;
  for (const MeshPlacement& m : spec.meshes) {
    if (bySpec.count(m.spec)) continue;
    LoadOptions lo;
    lo.placement = spec.placement;
    lo.properties = spec.properties;
    lo.vertexNormals = spec.vertexNormals;
    if (uses.at(m.spec) == 1) lo.transform = m.worldFromMesh;
    s.meshes.push_back(loadMesh(m.spec, lo));
    if (!quiet) logLoadedMesh(s.meshes.back());
    s.fileBytes += s.meshes.back().stats.fileBytes;
    bySpec[m.spec] = &s.meshes.back();
  }
  return bySpec;
}

/// World bounds: the directly attached meshes share the render origin (their float bounds
/// are merged, then offset in double); instances add their transformed bounding boxes.
void computeWorldBounds(LoadedScene& s) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  glm::dvec3 wlo(INFINITY), whi(-INFINITY);
  bool direct = false;
  for (const SceneObject& o : s.objects) {
    glm::vec3 a, b;
    o.mesh->bounds(a, b);
    if (o.worldFromMesh == glm::dmat4(1.0)) {
      lo = glm::min(lo, a), hi = glm::max(hi, b), direct = true;
      continue;
    }
    for (int c = 0; c < 8; ++c) {
      const glm::dvec3 local =
          o.mesh->anchor + glm::dvec3(c & 1 ? b.x : a.x, c & 2 ? b.y : a.y, c & 4 ? b.z : a.z);
      const glm::dvec3 w(o.worldFromMesh * glm::dvec4(local, 1.0));
      wlo = glm::min(wlo, w), whi = glm::max(whi, w);
    }
  }
  if (direct && lo.x <= hi.x) {
    wlo = glm::min(wlo, s.renderOrigin + glm::dvec3(lo));
    whi = glm::max(whi, s.renderOrigin + glm::dvec3(hi));
  }
  if (!(wlo.x <= whi.x)) wlo = whi = s.renderOrigin;
  s.worldLo = wlo;
  s.worldHi = whi;
}

void logBuild(const SceneSpec& spec, const LoadedScene& s) {
  const BuildStats& b = s.scene->stats();
  std::fprintf(
      stderr,
      "aperture: built BVH (%s%s%s): %zu triangles (%zu stored, %zu instances, %zu "
      "chunks, %.2f chunks per cell) in %.3f s, Embree memory %.1f MB (%.1f bytes/triangle)\n",
      bvhQualityName(spec.build.quality), spec.build.robust ? ", robust" : ", not robust",
      spec.build.compact ? ", compact" : "", b.triangles, b.uniqueTriangles,
      s.scene->instanceCount(), b.chunks, b.chunksPerCell, b.buildSeconds, b.embreeBytes / 1e6,
      b.triangles ? double(b.embreeBytes) / double(b.triangles) : 0.0);
}

}  // namespace

LoadedScene loadSceneMeshes(const SceneSpec& spec, bool quiet) {
  if (spec.meshes.empty()) throw Error("scene: no mesh");
  LoadedScene s;
  const auto start = std::chrono::steady_clock::now();
  const auto uses = usesOf(spec);
  const std::map<std::string, Mesh*> bySpec = loadDistinctMeshes(s, spec, uses, quiet);
  s.loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const MeshPlacement& m : spec.meshes) {
    const bool instanced = uses.at(m.spec) > 1;
    s.objects.push_back({bySpec.at(m.spec),
                         instanced ? m.worldFromMesh.value_or(glm::dmat4(1.0)) : glm::dmat4(1.0)});
    s.names.push_back(m.spec);
  }
  // Meshes used once share the render origin (the first object's anchor), so they are
  // attached directly rather than instanced.
  s.renderOrigin = renderOriginOf(s.objects);
  for (const auto& [name, mesh] : bySpec)
    if (uses.at(name) == 1) moveAnchor(*mesh, s.renderOrigin);
  computeWorldBounds(s);
  return s;
}

void orderScatteredMeshes(LoadedScene& s, const BuildOptions& build, bool quiet) {
  const std::vector<bool> direct = attachedDirectly(s.objects);
  for (size_t k = 0; k < s.objects.size(); ++k) {
    if (!direct[k]) continue;
    // A directly attached mesh is placed once: this object is its only user.
    Mesh& m = *std::find_if(s.meshes.begin(), s.meshes.end(),
                            [&](const Mesh& mesh) { return &mesh == s.objects[k].mesh; });
    const auto start = std::chrono::steady_clock::now();
    if (orderIfScattered(m, build) && !quiet)
      std::fprintf(stderr,
                   "aperture: %s: %zu triangles scattered in space, put in spatial order for a "
                   "chunked build in %.3f s (primIDs keep the file's order)\n",
                   m.name.c_str(), m.triangleCount(),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
}

void buildLoadedScene(const Device& device, LoadedScene& s, const SceneSpec& spec, bool quiet,
                      const std::vector<CameraParams>& cameras) {
  orderScatteredMeshes(s, spec.build, quiet);
  if (spec.cull) {
    if (cameras.empty()) throw Error("--cull: no camera is known to cull for");
    const CameraCuller culler = cullerFor(cameras, s.renderOrigin);
    if (culler.seesEverything) {
      if (!quiet)
        std::fprintf(stderr, "aperture: cull: a panorama camera sees all space; nothing culled\n");
    } else {
      s.cull = cullObjects(s.objects, culler.test(), s.subsets);
      if (!quiet) logCullStats(*s.cull, cameras.size());
    }
  }
  s.scene = std::make_unique<Scene>(device, s.objects, spec.build);
  if (!quiet) logBuild(spec, s);
}

LoadedScene loadedSceneOfMesh(Mesh mesh, const LoadOptions& options) {
  finishMesh(mesh, options);
  LoadedScene s;
  s.meshes.push_back(std::move(mesh));
  const Mesh& m = s.meshes.back();
  s.objects.push_back({&m, glm::dmat4(1.0)});
  s.names.push_back(m.name);
  s.renderOrigin = m.anchor;
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  s.worldLo = m.anchor + glm::dvec3(lo);
  s.worldHi = m.anchor + glm::dvec3(hi);
  return s;
}

LoadedScene loadScene(const Device& device, const SceneSpec& spec, bool quiet) {
  LoadedScene s = loadSceneMeshes(spec, quiet);
  buildLoadedScene(device, s, spec, quiet);
  return s;
}

}  // namespace aperture::app
