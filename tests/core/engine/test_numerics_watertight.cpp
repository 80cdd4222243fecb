// Numerics of watertightness: rays at shared edges and vertices, and the trace API against the
// frame loop. Part of the numerics tests (issue 5): each test checks a closed form or an
// independent path; the world-space float32 mode's errors are measured and printed
// (docs/numerics.md records them), not asserted.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/exr/exr.h"
#include "core/mesh/mesh.h"
#include "core/queries/trace.h"
#include "core/util/error.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using namespace aperture::test;

// --- Watertightness --------------------------------------------------------------------

struct WatertightCounts {
  size_t edgeRays = 0, edgeMisses = 0, vertexRays = 0, vertexMisses = 0;
};

// Rays aimed exactly (in render space, as float) at points of shared edges and at vertices of
// a closed mesh, from outside along the outward direction through the mesh's centre: each
// such ray passes through the interior, so a watertight intersector must hit something.
WatertightCounts shootAtEdgesAndVertices(const Mesh& m, const Scene& scene) {
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  const glm::dvec3 centre = 0.5 * (glm::dvec3(lo) + glm::dvec3(hi));
  const double reach = glm::length(glm::dvec3(hi) - glm::dvec3(lo));
  // The anchor of the mesh relative to the scene's render origin (0 in camera-relative mode).
  const glm::dvec3 shift = m.anchor - scene.renderOrigin();
  auto aim = [&](const glm::dvec3& target, std::vector<TraceRay>& rays) {
    const glm::dvec3 out = glm::normalize(target - centre);
    TraceRay r;
    r.org = glm::vec3(shift + target + reach * out);
    // Aim from the rounded origin at the target itself, so the ray passes through it.
    r.dir = glm::vec3(glm::normalize((shift + target) - glm::dvec3(r.org)));
    rays.push_back(r);
  };
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    for (int e = 0; e < 3; ++e) {
      uint32_t a = m.indices[3 * t + size_t(e)], b = m.indices[3 * t + size_t((e + 1) % 3)];
      if (a > b) std::swap(a, b);
      ++edges[{a, b}];
    }
  std::vector<TraceRay> edgeRays, vertexRays;
  for (const auto& [e, uses] : edges) {
    if (uses != 2) continue;  // shared edges only
    const glm::dvec3 a(m.vertex(e.first)), b(m.vertex(e.second));
    for (double s : {0.5, 0.25, 0.125, 0.999}) aim(a + s * (b - a), edgeRays);
  }
  for (size_t v = 0; v < m.vertexCount; ++v) aim(glm::dvec3(m.vertex(v)), vertexRays);
  WatertightCounts c;
  for (const TraceHit& h : traceRays(scene, edgeRays)) c.edgeMisses += !h.hit();
  for (const TraceHit& h : traceRays(scene, vertexRays)) c.vertexMisses += !h.hit();
  c.edgeRays = edgeRays.size();
  c.vertexRays = vertexRays.size();
  return c;
}

TEST(NumericsWatertight, RobustHasNoEdgeMissesFarFromTheOriginVertexMissesAreCounted) {
  std::printf(
      "[ info ] mesh at 1e6          | placement       | robust | edge misses | "
      "vertex misses\n");
  for (const char* spec :
       {"procedural:sphere?radius=3&segments=48&rings=24", "procedural:cube?size=2"}) {
    for (Placement pl : {Placement::CameraRelative, Placement::WorldSpace}) {
      for (bool robust : {true, false}) {
        LoadOptions lo;
        lo.placement = pl;
        lo.translate = glm::dvec3(1e6, -1e6, 1e6);
        BuildOptions bo;
        bo.robust = robust;
        const Loaded l = load(spec, lo, bo);
        const WatertightCounts c = shootAtEdgesAndVertices(*l.mesh, *l.scene);
        ASSERT_GT(c.edgeRays, 0u);
        std::printf("[ info ] %-20.20s | %-15s | %-6s | %5zu / %-5zu | %4zu / %zu\n", spec + 11,
                    pl == Placement::WorldSpace ? "world-space" : "camera-relative",
                    robust ? "yes" : "no", c.edgeMisses, c.edgeRays, c.vertexMisses, c.vertexRays);
        if (robust) {
          EXPECT_EQ(c.edgeMisses, 0u) << spec;
        }
      }
    }
  }
}

// The trace API agrees with the frame loop: the centre pixel's ray hits the same triangle at
// the same distance.
TEST(NumericsWatertight, TraceRaysMatchesTheFrameLoop) {
  const Loaded l = load("procedural:city");
  CameraParams p = lookAt(glm::dvec3(14, 11, 18), glm::dvec3(0, 1, 0), 33, 17);
  const Framebuffer fb = render(*l.scene, p, kAovDistance | kAovPrimId);
  const auto cam = makeCameraModel(p, l.scene->renderOrigin());
  std::vector<TraceRay> rays;
  for (int i = 0; i < p.height; ++i)
    for (int j = 0; j < p.width; ++j) {
      glm::dvec3 o, d;
      cam->ray(j + 0.5, i + 0.5, 0.5, 0.5, o, d);
      rays.push_back({glm::vec3(o), glm::vec3(d)});
    }
  for (int width : {1, 4, 8, 16}) {
    const std::vector<TraceHit> hits = traceRays(*l.scene, rays, width);
    for (size_t i = 0; i < hits.size(); ++i) {
      EXPECT_EQ(hits[i].primId, fb.primId[i]) << i;
      if (hits[i].hit()) {
        EXPECT_EQ(hits[i].t, fb.distance[i]) << i;
      }
    }
  }
  EXPECT_THROW(traceRays(*l.scene, rays, 3), Error);
  TraceRay bad;
  bad.dir = glm::vec3(std::numeric_limits<float>::quiet_NaN(), 0, -1);
  EXPECT_FALSE(traceRays(*l.scene, {bad})[0].hit());
}

}  // namespace
}  // namespace aperture
