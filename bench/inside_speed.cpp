// Throughput of insideOf (core/queries/inside.h): parity with 1 and 5 directions, each by
// the retrace (the scene as rendered) and in one traversal per ray (the same mesh built with
// BuildOptions::contextFilter), and the winding number, on N points spread uniformly over a
// mesh's box (enlarged by 10 % on each side, fixed seed); and countIntersections
// (core/queries/ray_hits.h) both ways on rays from those points in random directions. In
// alternating rounds; medians in points (rays) per second (bench/RESULTS.md).
//   aperture_inside_speed MESH [POINTS=1000000] [ROUNDS=3] [BETA=2; 0: no winding]
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/queries/inside.h"
#include "core/queries/ray_hits.h"
#include "core/queries/winding_number.h"
#include "core/queries/world_triangles.h"

namespace {

double seconds(const std::chrono::steady_clock::time_point& start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  using namespace aperture;
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s MESH [POINTS] [ROUNDS] [BETA]\n", argv[0]);
    return 2;
  }
  const size_t count = argc > 2 ? size_t(std::atoll(argv[2])) : 1000000;
  const int rounds = argc > 3 ? std::atoi(argv[3]) : 3;
  const double beta = argc > 4 ? std::atof(argv[4]) : 2.0;
  try {
    Device device;
    const Mesh mesh = loadMesh(argv[1]);
    const Scene scene(device, std::vector<const Mesh*>{&mesh});
    BuildOptions filterOptions;
    filterOptions.contextFilter = true;
    auto built = std::chrono::steady_clock::now();
    const Scene filterScene(device, std::vector<const Mesh*>{&mesh}, filterOptions);
    std::printf("context-filter scene: %.3f s\n", seconds(built));
    glm::vec3 lo, hi;
    mesh.bounds(lo, hi);
    const glm::dvec3 pad = 0.1 * glm::dvec3(hi - lo);
    const glm::dvec3 low = mesh.anchor + glm::dvec3(lo) - pad;
    const glm::dvec3 size = glm::dvec3(hi - lo) + 2.0 * pad;
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> points(3 * count);
    for (size_t i = 0; i < count; ++i)
      for (int c = 0; c < 3; ++c) points[3 * i + size_t(c)] = low[c] + size[c] * u(rng);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<double> directions(3 * count);
    for (size_t i = 0; i < count; ++i) {
      const glm::dvec3 d = glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)));
      for (int c = 0; c < 3; ++c) directions[3 * i + size_t(c)] = d[c];
    }
    std::printf("%s: %zu triangles, %zu points, %d rounds, beta %g\n", argv[1],
                mesh.triangleCount(), count, rounds, beta);

    std::printf("threads: %d (TBB default), Embree ISA %s\n",
                tbb::this_task_arena::max_concurrency(), device.isaName().c_str());
    auto start = std::chrono::steady_clock::now();
    const ClosedCheck closed = checkClosed(scene);
    std::printf(
        "checkClosed: %.3f s (closed %d, %zu edges, %zu boundary, %zu non-manifold, %zu "
        "misoriented)\n",
        seconds(start), int(closed.closed), closed.edges, closed.boundaryEdges,
        closed.nonManifoldEdges, closed.misorientedEdges);
    const bool winding = beta > 0;
    start = std::chrono::steady_clock::now();
    std::optional<WindingNumberTree> tree;
    if (winding) {
      tree.emplace(worldTriangleCorners(scene));
      std::printf("winding tree: %.3f s (%zu nodes)\n", seconds(start), tree->nodeCount());
    }

    struct Variant {
      const char* name;
      const Scene* scene;
      InsideOptions options;
      std::vector<double> times;
      InsideResult last;
    };
    std::vector<Variant> variants(winding ? 5 : 4);
    variants[0].name = "parity, 1 direction, retrace";
    variants[1].name = "parity, 1 direction, one trav.";
    variants[2].name = "parity, 5 directions, retrace";
    variants[3].name = "parity, 5 directions, one trav.";
    for (int k = 0; k < 4; ++k) {
      variants[size_t(k)].scene = k % 2 ? &filterScene : &scene;
      variants[size_t(k)].options.method = InsideMethod::Parity;
      variants[size_t(k)].options.parityDirections = k < 2 ? 1 : 5;
    }
    if (winding) {
      variants[4].name = "winding (tree kept)";
      variants[4].scene = &scene;
      variants[4].options.method = InsideMethod::Winding;
      variants[4].options.windingTree = &*tree;
    }
    for (Variant& v : variants) v.options.windingBeta = winding ? beta : 2.0;
    std::vector<double> countTimes[2];
    std::vector<uint32_t> counts[2];
    for (int r = 0; r < rounds; ++r) {
      for (Variant& v : variants) {
        start = std::chrono::steady_clock::now();
        v.last = insideOf(*v.scene, points.data(), count, v.options);
        v.times.push_back(seconds(start));
      }
      for (int k = 0; k < 2; ++k) {
        start = std::chrono::steady_clock::now();
        counts[k] =
            countIntersections(k ? filterScene : scene, points.data(), directions.data(), count);
        countTimes[k].push_back(seconds(start));
      }
    }
    const Variant& reference = variants.back();
    for (const Variant& v : variants) {
      size_t inside = 0, agree = 0;
      for (size_t i = 0; i < count; ++i) {
        inside += v.last.inside[i];
        agree += v.last.inside[i] == reference.last.inside[i];
      }
      std::printf(
          "%-32s median %.3f s  %.3g points/s  inside %.4f  differs from %s at %zu"
          "  discarded rays %zu%s\n",
          v.name, median(v.times), double(count) / median(v.times), double(inside) / double(count),
          reference.name, count - agree, v.last.discardedRays,
          &v - variants.data() == 1 || &v - variants.data() == 3
              ? (v.last.inside == (&v - 1)->last.inside ? "  equals retrace"
                                                        : "  DIFFERS from retrace")
              : "");
    }
    size_t hits = 0;
    for (uint32_t c : counts[0]) hits += c;
    for (int k = 0; k < 2; ++k)
      std::printf("%-32s median %.3f s  %.3g points/s  inside %.4f  hits %zu  equal %d\n",
                  k ? "count_intersections, one trav." : "count_intersections, retrace",
                  median(countTimes[k]), double(count) / median(countTimes[k]),
                  double(hits) / double(count), hits, int(counts[k] == counts[0]));
    if (!winding) return 0;
    double worstBound = 0;
    for (double b : reference.last.windingErrorBound) worstBound = std::max(worstBound, b);
    size_t uncertain = 0;
    for (size_t i = 0; i < count; ++i)
      uncertain += std::abs(reference.last.winding[i] - 0.5) <= reference.last.windingErrorBound[i];
    std::printf("winding: largest error bound %.3g; points whose |w - 0.5| <= bound: %.4f\n",
                worstBound, double(uncertain) / double(count));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
