#pragma once
// The scenes, cameras and independent pinhole of the visibility tests
// (tests/core/queries/test_visibility*.cpp).
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/queries/visibility.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture::test::visibility {

using test::Loaded;  // a mesh and its scene: sceneOf(mesh)
using test::sceneOf;

/// Triangles in world space, each added with its corners in the order given.
struct MeshBuilder {
  std::vector<glm::dvec3> vertices;
  std::vector<uint32_t> indices;

  void triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    for (const glm::dvec3& v : {a, b, c}) {
      indices.push_back(uint32_t(vertices.size()));
      vertices.push_back(v);
    }
  }
  /// Quad a b c d as the triangles (a, b, c) and (a, c, d): its diagonal runs from a to c.
  void quad(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& d) {
    triangle(a, b, c);
    triangle(a, c, d);
  }
  Mesh mesh(const glm::dvec3& anchor = glm::dvec3(0.0)) const {
    Mesh m;
    m.name = "visibility test";
    m.anchor = anchor;
    m.vertexCount = vertices.size();
    for (const glm::dvec3& v : vertices)
      for (int c = 0; c < 3; ++c) m.positions.push_back(float(v[c] - anchor[c]));
    m.positions.resize(m.positions.size() + kVertexPaddingFloats, 0.0f);
    m.indices.assign(indices.begin(), indices.end());
    return m;
  }
};

/// Cameras built with the scene's render origin, and the pointers the API takes.
struct Cameras {
  std::vector<std::unique_ptr<Camera>> owned;
  std::vector<const Camera*> list;
  Cameras(const Scene& scene, const std::vector<CameraParams>& params) {
    for (const CameraParams& p : params) {
      owned.push_back(makeCamera(p, scene.renderOrigin()));
      list.push_back(owned.back().get());
    }
  }
};

inline CameraParams perspective(glm::dvec3 eye, glm::dvec3 at, glm::dvec3 up, int w, int h,
                                double fovDeg) {
  CameraParams p;
  p.eye = eye, p.at = at, p.up = up;
  p.width = w, p.height = h;
  p.fovDeg = fovDeg;
  return p;
}

inline std::vector<uint32_t> row(const SparseRows& rows, size_t r) {
  return {rows.indices.begin() + long(rows.indptr[r]),
          rows.indices.begin() + long(rows.indptr[r + 1])};
}

/// World corners of triangle f of a mesh, in double (anchor + float positions).
struct Corners {
  glm::dvec3 a, b, c;
};
inline Corners cornersOf(const Mesh& m, size_t f) {
  auto v = [&](int k) { return m.anchor + glm::dvec3(m.vertex(m.indices[3 * f + size_t(k)])); };
  return {v(0), v(1), v(2)};
}

/// The test's own pinhole (independent of cameras/): frame W = (eye − at)/|.|, U = up × W,
/// V = W × U; focal length in pixels f = (H / 2) / tan(fov / 2) (vertical fov); raster
/// x = W/2 + f·(q·U)/z, y = H/2 − f·(q·V)/z with q = p − eye and depth z = −q·W.
struct Pinhole {
  glm::dvec3 eye, u, v, w;
  double f, width, height;
  explicit Pinhole(const CameraParams& p)
      : eye(p.eye),
        w(glm::normalize(p.eye - *p.at)),
        f(0.5 * p.height / std::tan(0.5 * *p.fovDeg * test::kDeg)),
        width(p.width),
        height(p.height) {
    u = glm::normalize(glm::cross(p.up, w));
    v = glm::cross(w, u);
  }
  std::optional<glm::dvec2> raster(const glm::dvec3& p) const {
    const glm::dvec3 q = p - eye;
    const double z = -glm::dot(q, w);
    if (!(z > 0)) return std::nullopt;
    return glm::dvec2(0.5 * width + f * glm::dot(q, u) / z, 0.5 * height - f * glm::dot(q, v) / z);
  }
  bool inside(const glm::dvec2& r) const {
    return r.x >= 0 && r.x < width && r.y >= 0 && r.y < height;
  }
};

}  // namespace aperture::test::visibility
