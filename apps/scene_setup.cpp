#include "apps/scene_setup.h"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "cameras/culling.h"
#include "core/error.h"
#include "core/limits.h"

namespace aperture::app {

void checkMemoryBudget(const SceneOptions& o, glm::ivec2 size, AovMask aovs,
                       uint64_t extraBytesPerPixel) {
  const uint64_t limit = parseMemoryLimit("--max-memory", o.maxMemory);
  if (limit == 0) return;
  std::vector<std::string> specs = o.meshes;
  if (specs.empty()) specs.push_back("procedural:default");
  const MemoryEstimate e =
      estimateMemory(specs, uint64_t(size.x), uint64_t(size.y), aovs, extraBytesPerPixel);
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
  return b;
}

void addSceneOptions(CLI::App& app, SceneOptions& o) {
  app.add_option(
      "--mesh", o.meshes,
      "Mesh file (.ply, .obj) or procedural:NAME?k=v (e.g. procedural:spheres?tris=2000000);"
      " repeatable. Default: the procedural default scene");
  app.add_option("--bvh-quality", o.quality, "Embree BVH build quality: low, medium, high")
      ->capture_default_str();
  app.add_flag("--robust", o.robust, "Embree robust (watertight) traversal");
  app.add_flag("--compact", o.compact, "Embree compact BVH (less memory, slower)");
  app.add_flag("--cull", o.cull,
               "Build the BVH over only the triangles the camera's view volume may reach "
               "(conservative: the image is bit-identical; panoramas keep all)");
  app.add_option("--max-memory", o.maxMemory,
                 "Refuse the job before loading when its estimated memory (mesh buffers from "
                 "the file headers, ~80 bytes/triangle of BVH, framebuffers) exceeds BYTES "
                 "(suffix K, M, G, T) or, with 'auto', MemAvailable");
  app.add_flag("--world-space", o.worldSpace,
               "Store vertices as float32 world coordinates instead of relative to the mesh's "
               "bounding-box centre (camera-relative, the default); for measuring the difference");
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

std::vector<Mesh> loadMeshes(const SceneOptions& o, bool quiet) {
  std::vector<std::string> specs = o.meshes;
  if (specs.empty()) specs.push_back("procedural:default");
  std::vector<Mesh> meshes;
  for (const std::string& spec : specs) {
    meshes.push_back(loadMesh(spec, o.loadOptions()));
    if (!quiet) logLoadedMesh(meshes.back());
  }
  // Meshes share the first one's anchor (moved in double) so they share one render space.
  for (size_t k = 1; k < meshes.size(); ++k) moveAnchor(meshes[k], meshes[0].anchor);
  return meshes;
}

void moveAnchor(Mesh& m, const glm::dvec3& anchor) {
  const glm::dvec3 delta = m.anchor - anchor;
  for (size_t v = 0; v < m.vertexCount; ++v)
    for (int c = 0; c < 3; ++c)
      m.positions[3 * v + c] = float(double(m.positions[3 * v + c]) + delta[c]);
  m.anchor = anchor;
}

LoadedScene loadSceneMeshes(const SceneOptions& o, bool quiet) {
  LoadedScene s;
  const auto start = std::chrono::steady_clock::now();
  s.meshes = loadMeshes(o, quiet);
  s.loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const Mesh& m : s.meshes) {
    s.objects.push_back({&m, glm::dmat4(1.0), nullptr});
    s.fileBytes += m.stats.fileBytes;
    glm::vec3 a, b;
    m.bounds(a, b);
    lo = glm::min(lo, a);
    hi = glm::max(hi, b);
  }
  if (!(lo.x <= hi.x)) lo = hi = glm::vec3(0.0f);
  s.worldLo = s.meshes[0].anchor + glm::dvec3(lo);
  s.worldHi = s.meshes[0].anchor + glm::dvec3(hi);
  return s;
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

void buildLoadedScene(const Device& device, LoadedScene& s, const SceneOptions& o, bool quiet,
                      const std::vector<CameraParams>& cameras) {
  if (o.cull) {
    if (cameras.empty()) throw Error("--cull: no camera is known to cull for");
    // Untransformed meshes sharing the first anchor: the render origin is that anchor.
    const CameraCuller culler = cullerFor(cameras, s.meshes[0].anchor);
    if (culler.seesEverything) {
      if (!quiet)
        std::fprintf(stderr,
                     "aperture: --cull: a panorama camera sees all space; nothing culled\n");
    } else {
      s.cull = cullObjects(s.objects, culler.test(), s.subsets);
      if (!quiet) logCullStats(*s.cull, cameras.size());
    }
  }
  s.scene = std::make_unique<Scene>(device, s.objects, o.buildOptions());
  if (!quiet) {
    const BuildStats& b = s.scene->stats();
    std::fprintf(stderr,
                 "aperture: built BVH (%s%s%s): %zu triangles in %.3f s, Embree memory %.1f MB "
                 "(%.1f bytes/triangle)\n",
                 bvhQualityName(o.buildOptions().quality), o.robust ? ", robust" : "",
                 o.compact ? ", compact" : "", b.triangles, b.buildSeconds, b.embreeBytes / 1e6,
                 b.triangles ? double(b.embreeBytes) / double(b.triangles) : 0.0);
  }
}

LoadedScene loadScene(const Device& device, const SceneOptions& o, bool quiet) {
  LoadedScene s = loadSceneMeshes(o, quiet);
  buildLoadedScene(device, s, o, quiet);
  return s;
}

}  // namespace aperture::app
