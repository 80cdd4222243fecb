#include "apps/batch_scene.h"

#include <cstdio>
#include <map>

#include "apps/batch_progress.h"
#include "apps/scene_setup.h"
#include "cameras/culling.h"

namespace aperture::app {

namespace {

/// Loads each distinct mesh file once; fills `bySpec`.
void loadMeshes(BatchScene& s, const Job& job, const std::map<std::string, size_t>& uses,
                bool quiet, std::map<std::string, Mesh*>& bySpec) {
  const auto start = BatchClock::now();
  for (const JobMesh& m : job.meshes) {
    if (bySpec.count(m.spec)) continue;
    LoadOptions lo;
    lo.placement = job.placement;
    if (uses.at(m.spec) == 1) lo.transform = m.worldFromMesh;
    s.meshes.push_back(loadMesh(m.spec, lo));
    if (!quiet) logLoadedMesh(s.meshes.back());
    bySpec[m.spec] = &s.meshes.back();
  }
  s.loadSeconds = secondsSince(start);
}

void cullScene(BatchScene& s, std::vector<SceneObject>& objects, const glm::dvec3& origin,
               bool quiet, const std::vector<CameraParams>& cameras) {
  const CameraCuller culler = cullerFor(cameras, origin);
  if (culler.seesEverything) {
    if (!quiet)
      std::fprintf(stderr, "aperture: cull: a panorama camera sees all space; nothing culled\n");
    return;
  }
  const CullStats c = cullObjects(objects, culler.test(), s.subsets);
  if (!quiet) logCullStats(c, cameras.size());
}

void logBuild(const Job& job, const Scene& scene) {
  const BuildStats& b = scene.stats();
  std::fprintf(stderr,
               "aperture: built BVH (%s%s%s): %zu triangles (%zu stored, %zu instances) in "
               "%.3f s, Embree memory %.1f MB\n",
               bvhQualityName(job.build.quality), job.build.robust ? ", robust" : "",
               job.build.compact ? ", compact" : "", b.triangles, b.uniqueTriangles,
               scene.instanceCount(), b.buildSeconds, b.embreeBytes / 1e6);
}

}  // namespace

BatchScene buildBatchScene(const Device& device, const Job& job, bool quiet,
                           const std::vector<CameraParams>& cameras) {
  BatchScene s;
  std::map<std::string, size_t> uses;
  for (const JobMesh& m : job.meshes) ++uses[m.spec];
  std::map<std::string, Mesh*> bySpec;
  loadMeshes(s, job, uses, quiet, bySpec);

  std::vector<SceneObject> objects;
  for (const JobMesh& m : job.meshes) {
    const bool instanced = uses[m.spec] > 1;
    objects.push_back(
        {bySpec[m.spec], instanced ? m.worldFromMesh.value_or(glm::dmat4(1.0)) : glm::dmat4(1.0)});
    s.names.push_back(m.spec);
  }
  // Meshes used once share the render origin (the first object's anchor), so they are
  // attached directly rather than instanced.
  const glm::dvec3 origin(objects[0].worldFromMesh * glm::dvec4(objects[0].mesh->anchor, 1.0));
  for (auto& [spec, mesh] : bySpec)
    if (uses[spec] == 1) moveAnchor(*mesh, origin);
  if (job.cull && !cameras.empty()) cullScene(s, objects, origin, quiet, cameras);
  s.scene = std::make_unique<Scene>(device, objects, job.build);
  if (!quiet) logBuild(job, *s.scene);
  return s;
}

}  // namespace aperture::app
