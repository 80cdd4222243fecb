#include "core/queries/world_triangles.h"

#include "core/util/parallel.h"

namespace aperture {

WorldObjects worldObjects(const Scene& scene) {
  WorldObjects all;
  for (const SceneObject& o : scene.objects()) {
    WorldObject w;
    w.mesh = o.mesh;
    w.indices = o.subset ? o.subset->indices.data() : o.mesh->indices.data();
    w.triangles = o.subset ? o.subset->triangleCount() : o.mesh->triangleCount();
    w.firstTriangle = all.triangles;
    w.firstVertex = all.vertices;
    w.anchor = o.mesh->anchor;
    w.worldFromMesh = o.worldFromMesh;
    all.triangles += w.triangles;
    all.vertices += o.mesh->vertexCount;
    all.objects.push_back(w);
  }
  return all;
}

std::vector<glm::dvec3> worldTriangleCorners(const Scene& scene) {
  const WorldObjects all = worldObjects(scene);
  std::vector<glm::dvec3> corners(3 * all.triangles);
  for (const WorldObject& o : all.objects) {
    glm::dvec3* out = corners.data() + 3 * o.firstTriangle;
    parallelFor(3 * o.triangles, 1 << 16, [&](size_t begin, size_t end) {
      const WorldObject placed = o;  // local: `out` cannot alias it
      for (size_t k = begin; k < end; ++k) out[k] = placed.vertex(placed.indices[k]);
    });
  }
  return corners;
}

}  // namespace aperture
