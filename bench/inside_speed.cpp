// Throughput of insideOf (core/queries/inside.h): parity with 1 and 5 directions and the
// winding number, on N points spread uniformly over a mesh's box (enlarged by 10 % on each
// side, fixed seed), in alternating rounds; medians in points per second (bench/RESULTS.md).
//   aperture_inside_speed MESH [POINTS=1000000] [ROUNDS=3] [BETA=2] [winding]
// A fifth argument `winding` times the winding number alone (for profiling it). The CPU
// seconds (all threads) are steadier than wall time on a loaded machine with one thread
// (taskset -c 0).
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <string>
#include <vector>

#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/queries/inside.h"
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
    std::fprintf(stderr, "usage: %s MESH [POINTS] [ROUNDS] [BETA] [winding]\n", argv[0]);
    return 2;
  }
  const size_t count = argc > 2 ? size_t(std::atoll(argv[2])) : 1000000;
  const int rounds = argc > 3 ? std::atoi(argv[3]) : 3;
  const double beta = argc > 4 ? std::atof(argv[4]) : 2.0;
  const bool windingOnly = argc > 5 && std::string(argv[5]) == "winding";
  try {
    Device device;
    const Mesh mesh = loadMesh(argv[1]);
    const Scene scene(device, std::vector<const Mesh*>{&mesh});
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
    start = std::chrono::steady_clock::now();
    const WindingNumberTree tree(worldTriangleCorners(scene));
    std::printf("winding tree: %.3f s (%zu nodes)\n", seconds(start), tree.nodeCount());

    struct Variant {
      const char* name;
      InsideOptions options;
      std::vector<double> times, cpu;  // wall and process CPU seconds
      InsideResult last;
    };
    std::vector<Variant> variants(3);
    variants[0].name = "parity, 1 direction";
    variants[0].options.method = InsideMethod::Parity;
    variants[1].name = "parity, 5 directions";
    variants[1].options.method = InsideMethod::Parity;
    variants[1].options.parityDirections = 5;
    variants[2].name = "winding (tree kept)";
    variants[2].options.method = InsideMethod::Winding;
    variants[2].options.windingTree = &tree;
    for (Variant& v : variants) v.options.windingBeta = beta;
    if (windingOnly) variants.erase(variants.begin(), variants.begin() + 2);
    for (int r = 0; r < rounds; ++r)
      for (Variant& v : variants) {
        start = std::chrono::steady_clock::now();
        const std::clock_t cpuStart = std::clock();
        v.last = insideOf(scene, points.data(), count, v.options);
        v.times.push_back(seconds(start));
        v.cpu.push_back(double(std::clock() - cpuStart) / CLOCKS_PER_SEC);
      }
    for (const Variant& v : variants) {
      size_t inside = 0, agree = 0;
      for (size_t i = 0; i < count; ++i) {
        inside += v.last.inside[i];
        agree += v.last.inside[i] == variants.back().last.inside[i];
      }
      std::printf(
          "%-30s median %.3f s (CPU %.3f s)  %.3g points/s  inside %.4f  differs from winding at "
          "%zu"
          "  discarded rays %zu\n",
          v.name, median(v.times), median(v.cpu), double(count) / median(v.times),
          double(inside) / double(count), count - agree, v.last.discardedRays);
    }
    double worstBound = 0;
    for (double b : variants.back().last.windingErrorBound) worstBound = std::max(worstBound, b);
    size_t uncertain = 0;
    for (size_t i = 0; i < count; ++i)
      uncertain += std::abs(variants.back().last.winding[i] - 0.5) <=
                   variants.back().last.windingErrorBound[i];
    uint64_t sides = 1469598103934665603ull;  // FNV-1a of the winding sides, to compare builds
    for (uint8_t in : variants.back().last.inside) sides = (sides ^ in) * 1099511628211ull;
    std::printf(
        "winding: largest error bound %.3g; points whose |w - 0.5| <= bound: %.4f; sides hash "
        "%016llx\n",
        worstBound, double(uncertain) / double(count), (unsigned long long)sides);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
