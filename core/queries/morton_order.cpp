#include "core/queries/morton_order.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "core/util/morton.h"
#include "core/util/parallel.h"

namespace aperture {

std::vector<size_t> mortonOrder(const double* points, size_t count, const glm::dvec3& lo,
                                const glm::dvec3& hi) {
  std::vector<std::pair<uint64_t, size_t>> keyed(count);
  const glm::dvec3 size = glm::max(hi - lo, glm::dvec3(1e-300));
  parallelFor(count, 1 << 14, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      uint64_t key = 0;
      for (int a = 0; a < 3; ++a) {
        const double u = (points[3 * i + size_t(a)] - lo[a]) / size[a];
        const double q = std::isnan(u) ? 0.0 : std::clamp(u, 0.0, 1.0) * 2097151.0;
        key |= spreadBits(uint64_t(q)) << a;
      }
      keyed[i] = {key, i};
    }
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<size_t> order(count);
  parallelFor(count, 1 << 14, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) order[i] = keyed[i].second;
  });
  return order;
}

}  // namespace aperture
