#include "core/queries/world_triangles.h"

#include "core/util/parallel.h"

namespace aperture {

std::vector<glm::dvec3> worldTriangleCorners(const Scene& scene) {
  size_t total = 0;
  for (const SceneObject& o : scene.objects())
    total += o.subset ? o.subset->triangleCount() : o.mesh->triangleCount();
  std::vector<glm::dvec3> corners(3 * total);
  size_t first = 0;
  for (const SceneObject& o : scene.objects()) {
    const Mesh& m = *o.mesh;
    const uint32_t* indices = o.subset ? o.subset->indices.data() : m.indices.data();
    const size_t triangles = o.subset ? o.subset->triangleCount() : m.triangleCount();
    const glm::dmat4 worldFromMesh = o.worldFromMesh;
    const glm::dvec3 anchor = m.anchor;
    glm::dvec3* out = corners.data() + 3 * first;
    parallelFor(3 * triangles, 1 << 16, [&](size_t begin, size_t end) {
      for (size_t k = begin; k < end; ++k) {
        const glm::dvec3 local = anchor + glm::dvec3(m.vertex(indices[k]));
        out[k] = glm::dvec3(worldFromMesh * glm::dvec4(local, 1.0));
      }
    });
    first += triangles;
  }
  return corners;
}

}  // namespace aperture
