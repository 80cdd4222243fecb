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
#include "core/io/texture_sampler.h"
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
  // The albedo AOV samples textures through the image codec (core/io/texture_sampler.h).
  if (imageCodec || aovs.has(kAovAlbedo)) e.imageCodecBytes = kImageCodecBytes;
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
  s.gltfScene = gltfScene;
  return withAovNeeds(s, aovs);
}

SceneSpec withAovNeeds(SceneSpec spec, const AovSet& aovs) {
  spec.properties = aovs.properties;
  spec.vertexNormals = aovs.has(kAovShadingNormal);
  // albedo = base colour x texture(uv) x vertex colour, per triangle's material.
  const bool albedo = aovs.has(kAovAlbedo);
  spec.texcoords = albedo || aovs.has(kAovUv);
  spec.vertexColors = albedo || aovs.has(kAovVertexColor);
  spec.materials = albedo || aovs.has(kAovMaterialId);
  spec.groups = aovs.has(kAovInstanceId);
  spec.textures = albedo;
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

/// What every file is loaded with (no transform: finishMesh gets it per mesh).
LoadOptions fileLoadOptions(const SceneSpec& spec) {
  LoadOptions lo;
  lo.placement = spec.placement;
  lo.properties = spec.properties;
  lo.vertexNormals = spec.vertexNormals;
  lo.texcoords = spec.texcoords;
  lo.vertexColors = spec.vertexColors;
  lo.materials = spec.materials;
  lo.groups = spec.groups;
  lo.gltfScene = spec.gltfScene;
  return lo;
}

/// `placement` · `inFile`, or nothing when both are the identity (finishMesh's untransformed
/// path, which a PLY placed without a transform has always taken).
std::optional<glm::dmat4> composed(const std::optional<glm::dmat4>& placement,
                                   const glm::dmat4& inFile) {
  if (inFile == glm::dmat4(1.0)) return placement;
  if (!placement) return inFile;
  return *placement * inFile;
}

/// One distinct file as loaded: its scene file (meshes moved out once finished), where its
/// meshes went and where its textures start among the scene's.
struct LoadedFile {
  SceneFile file;
  std::vector<Mesh*> finished;   ///< per file mesh; null for one no instance places
  std::vector<size_t> placedBy;  ///< per file mesh: how many of its instances place it
  size_t textureBase = 0;        ///< into LoadedScene::textures
};

/// Logs a file of several meshes or placements (one line; a single mesh logs as before).
void logLoadedFile(const LoadedFile& f, double seconds) {
  size_t triangles = 0, vertices = 0, meshes = 0;
  for (const Mesh* m : f.finished)
    if (m) triangles += m->triangleCount(), vertices += m->vertexCount, ++meshes;
  std::fprintf(stderr,
               "aperture: loaded %s: %zu meshes placed by %zu instances (%zu nodes), %zu "
               "triangles, %zu vertices, %zu materials in %.3f s",
               f.file.path.c_str(), meshes, f.file.instances.size(), f.file.instanceNames.size(),
               triangles, vertices, f.file.materials.size(), seconds);
  if (f.file.fileBytes)
    std::fprintf(stderr, " (%.1f MB/s)", f.file.fileBytes / 1e6 / std::max(seconds, 1e-9));
  std::fprintf(stderr, "\n");
}

/// Loads each distinct file once and finishes the meshes its scene places: with the whole
/// transform baked in when the mesh is placed once overall, else untransformed.
std::map<std::string, LoadedFile> loadDistinctFiles(LoadedScene& s, const SceneSpec& spec,
                                                    const std::map<std::string, size_t>& uses,
                                                    bool quiet) {
  std::map<std::string, LoadedFile> files;
  const LoadOptions fileOptions = fileLoadOptions(spec);
  for (const MeshPlacement& p : spec.meshes) {
    if (files.count(p.spec)) continue;
    const auto start = std::chrono::steady_clock::now();
    LoadedFile& f = files[p.spec];
    f.file = loadSceneFile(p.spec, fileOptions);
    f.finished.assign(f.file.meshes.size(), nullptr);
    f.placedBy.assign(f.file.meshes.size(), 0);
    for (const MeshInstance& in : f.file.instances) {
      if (in.mesh >= f.file.meshes.size())
        throw Error(cat(p.spec, ": instance ", in.id, " places mesh ", in.mesh, " of ",
                        f.file.meshes.size()));
      ++f.placedBy[in.mesh];
    }
    const bool once = uses.at(p.spec) == 1;
    for (const MeshInstance& in : f.file.instances) {
      if (f.finished[in.mesh]) continue;
      LoadOptions lo = fileOptions;
      if (once && f.placedBy[in.mesh] == 1)
        lo.transform = composed(p.worldFromMesh, in.worldFromMesh);
      Mesh& mesh = f.file.meshes[in.mesh];
      finishMesh(mesh, lo);
      s.meshes.push_back(std::move(mesh));
      mesh = Mesh();  // the file keeps nothing of it
      f.finished[in.mesh] = &s.meshes.back();
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool single = f.file.meshes.size() == 1 && f.file.instances.size() == 1;
    if (single) f.finished[0]->stats.loadSeconds = seconds;
    if (!quiet) {
      if (single)
        logLoadedMesh(*f.finished[0]);
      else
        logLoadedFile(f, seconds);
      if (f.file.skippedPrimitives)
        std::fprintf(stderr,
                     "aperture: warning: %s: %zu primitives of points or lines skipped (only "
                     "triangles are rendered)\n",
                     p.spec.c_str(), f.file.skippedPrimitives);
    }
    s.fileBytes += f.file.fileBytes;
    // Only the albedo AOV samples textures: embedded images are not kept otherwise.
    f.textureBase = s.textures.size();
    if (spec.textures)
      for (SurfaceTexture& t : f.file.textures) s.textures.push_back(std::move(t));
    f.file.meshes.clear();
    f.file.textures.clear();
  }
  return files;
}

/// Appends the objects, ids and materials of one placement of `f`. With `albedo`, a material
/// whose base colour is unknown (Material::unsupported) is an Error.
void placeFile(LoadedScene& s, const MeshPlacement& p, const LoadedFile& f, bool instanced,
               bool albedo) {
  const ObjectIds base{uint32_t(s.ids.instance.size()), uint32_t(s.ids.mesh.size()),
                       uint32_t(s.ids.material.size())};
  for (const MeshInstance& in : f.file.instances) {
    const bool baked = !instanced && f.placedBy[in.mesh] == 1;
    const glm::dmat4 worldFromMesh =
        baked ? glm::dmat4(1.0)
              : composed(p.worldFromMesh, in.worldFromMesh).value_or(glm::dmat4(1.0));
    s.objects.emplace_back(
        f.finished[in.mesh], worldFromMesh, nullptr,
        ObjectIds{base.instance + in.id, base.mesh + uint32_t(in.mesh), base.materialBase});
  }
  const SceneFile& file = f.file;
  s.ids.instance.insert(s.ids.instance.end(), file.instanceNames.begin(), file.instanceNames.end());
  s.ids.mesh.insert(s.ids.mesh.end(), file.meshNames.begin(), file.meshNames.end());
  s.ids.material.insert(s.ids.material.end(), file.materialNames.begin(), file.materialNames.end());
  for (size_t k = 0; k < file.materials.size(); ++k) {
    Material m = file.materials[k];
    if (albedo && !m.unsupported.empty())
      throw Error(cat(p.spec, ": material ", k, " '", m.name, "': its base colour needs ",
                      m.unsupported,
                      ", which aperture does not support: the albedo AOV cannot be rendered of "
                      "this file (the other AOVs can)"));
    if (m.baseColorTexture >= 0) m.baseColorTexture += int(f.textureBase);
    s.materials.push_back(std::move(m));
  }
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

/// The scene's SurfaceLooks: its materials and, for the albedo AOV, their textures' sampler.
void setSurfaceLooks(LoadedScene& s, const SceneSpec& spec) {
  if (s.materials.empty()) return;
  auto looks = std::make_shared<SurfaceLooks>();
  looks->materials = s.materials;
  if (spec.textures && !s.textures.empty()) looks->textures = openTextureSampler(s.textures);
  s.scene->setLooks(std::move(looks));
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
  if (spec.gltfScene && *spec.gltfScene < 0)
    throw Error(cat("--gltf-scene ", *spec.gltfScene, ": must be >= 0"));
  if (spec.gltfScene && std::none_of(spec.meshes.begin(), spec.meshes.end(),
                                     [](const MeshPlacement& m) { return isGltfPath(m.spec); }))
    throw Error(cat("--gltf-scene ", *spec.gltfScene,
                    ": no glTF file (.gltf, .glb) among the meshes to choose a scene of"));
  LoadedScene s;
  const auto start = std::chrono::steady_clock::now();
  const auto uses = usesOf(spec);
  const std::map<std::string, LoadedFile> files = loadDistinctFiles(s, spec, uses, quiet);
  s.loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const MeshPlacement& m : spec.meshes) {
    placeFile(s, m, files.at(m.spec), uses.at(m.spec) > 1, spec.textures);
    s.names.push_back(m.spec);
  }
  if (s.objects.empty())
    throw Error(cat("scene: the meshes place no triangles (", join(s.names, ", "),
                    " hold no mesh placed by a node of the loaded scene)"));
  // Meshes placed once share the render origin (the first object's anchor), so they are
  // attached directly rather than instanced.
  s.renderOrigin = renderOriginOf(s.objects);
  for (const auto& [name, f] : files)
    for (size_t k = 0; k < f.finished.size(); ++k)
      if (f.finished[k] && uses.at(name) == 1 && f.placedBy[k] == 1)
        moveAnchor(*f.finished[k], s.renderOrigin);
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
  setSurfaceLooks(s, spec);
  if (!quiet) logBuild(spec, s);
}

LoadedScene loadedSceneOfMesh(Mesh mesh, const LoadOptions& options) {
  finishMesh(mesh, options);
  LoadedScene s;
  s.meshes.push_back(std::move(mesh));
  const Mesh& m = s.meshes.back();
  s.objects.push_back({&m, glm::dmat4(1.0)});
  s.names.push_back(m.name);
  s.ids.instance = {m.name};
  s.ids.mesh = {m.name};
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
