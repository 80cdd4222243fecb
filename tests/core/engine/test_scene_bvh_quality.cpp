// The BVH build qualities. Embree documents what a quality is for (RTC_BUILD_QUALITY_HIGH:
// "for certain geometry types this enables a spatial split BVH", rtcSetSceneBuildQuality),
// not what its builder makes of it: the BVH's bytes, and whether a robust build uses spatial
// splits, depend on the Embree release and on the CPU's kernels (on an AMD Zen 4 with
// AVX-512, non-robust high came out 0.3 % smaller than medium; on an Intel Xeon 5 % larger).
// So these tests hold what must not depend on either: every quality, robust or not, traces
// the same scene. The bytes are printed, not asserted (bench/RESULTS.md has the sweep).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/queries/trace.h"
#include "tests/numerics_support.h"

namespace aperture {
namespace {

/// The procedural spheres (200,000 triangles, which spatial splits reach).
const Mesh& spheres() {
  static const Mesh m = [] {
    Mesh s = makeProcedural("procedural:spheres?tris=200000");
    finishMesh(s, LoadOptions{});
    return s;
  }();
  return m;
}

glm::vec3 vertex(const Mesh& m, uint32_t k) {
  return glm::vec3(m.positions[3 * k], m.positions[3 * k + 1], m.positions[3 * k + 2]);
}

/// One ray per sampled well-shaped triangle, towards its centroid along the winding normal from a
/// tenth of the triangle's size outside it, and the distance to the centroid: whatever the
/// BVH, the first hit is that triangle at that distance (a closed form, not another build).
struct CentroidRays {
  std::vector<TraceRay> rays;
  std::vector<uint32_t> triangle;
  std::vector<float> distance;
};

CentroidRays centroidRays(const Mesh& m) {
  CentroidRays out;
  for (uint32_t t = 0; t < m.triangleCount(); t += 211) {
    const glm::vec3 a = vertex(m, m.indices[3 * t]), b = vertex(m, m.indices[3 * t + 1]),
                    c = vertex(m, m.indices[3 * t + 2]);
    const glm::vec3 g = glm::cross(b - a, c - a);
    const float area2 = glm::length(g);
    // Well-shaped triangles only: near a sphere's poles the slivers of the fan are so thin
    // that the ray's start, a tenth of the size out, lies beyond a neighbour.
    const float longest2 =
        std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
    if (!(area2 > 0.25f * longest2)) continue;
    const float offset = 0.1f * std::sqrt(area2);
    TraceRay r;
    r.dir = -g / area2;
    r.org = (a + b + c) / 3.0f - offset * r.dir;
    out.rays.push_back(r);
    out.triangle.push_back(t);
    out.distance.push_back(offset);
  }
  return out;
}

TEST(BvhQuality, EveryQualityRobustOrNotHitsEachTriangleWhereItIs) {
  const Mesh& m = spheres();
  const CentroidRays c = centroidRays(m);
  ASSERT_GT(c.rays.size(), 500u);
  for (BvhQuality quality : {BvhQuality::Low, BvhQuality::Medium, BvhQuality::High})
    for (bool robust : {true, false}) {
      BuildOptions b;
      b.quality = quality;
      b.robust = robust;
      const Scene scene(test::numericsDevice(), {&m}, b);
      ASSERT_EQ(scene.renderOrigin(), m.anchor);  // the rays are in the mesh's own frame
      std::printf(
          "[ info ] BVH %s%s: %lld bytes (Embree's choice on this CPU, not asserted); "
          "%zu centroid rays\n",
          bvhQualityName(quality), robust ? " robust" : "", scene.stats().embreeBytes,
          c.rays.size());
      const std::vector<TraceHit> hits = traceRays(scene, c.rays, 16);
      size_t wrong = 0;
      for (size_t k = 0; k < hits.size(); ++k) {
        const bool right = hits[k].primId == c.triangle[k] &&
                           std::fabs(hits[k].t - c.distance[k]) <= 1e-3f * c.distance[k];
        if (!right && ++wrong <= 3)
          ADD_FAILURE() << bvhQualityName(quality) << (robust ? " robust" : "") << ": triangle "
                        << c.triangle[k] << " hit as " << hits[k].primId << " at t " << hits[k].t
                        << " (expected " << c.distance[k] << ")";
      }
      EXPECT_EQ(wrong, 0u) << bvhQualityName(quality) << (robust ? " robust" : "");
    }
}

}  // namespace
}  // namespace aperture
