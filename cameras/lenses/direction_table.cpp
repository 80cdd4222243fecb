#include "cameras/lenses/direction_table.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <list>
#include <mutex>
#include <set>

#include "core/util/huge_pages.h"
#include "core/util/parallel.h"

namespace aperture {

std::optional<glm::dvec3> sensorDirection(const CalibratedSensor& sensor, double x, double y) {
  return sensor.lens.unproject(sourcePixelOfRaster(glm::dvec2(x, y), sensor.pixelCentre));
}

DirectionTable::DirectionTable(const CalibratedSensor& sensor)
    : sensor_(sensor), blocksPerRow_(size_t((sensor.width + kBlock - 1) / kBlock)) {
  const size_t blockRows = size_t((sensor.height + kBlock - 1) / kBlock);
  const size_t n = blockRows * blocksPerRow_ * size_t(kBlock * kBlock);
  // Sized without being written (LargeBuffers): the rows' tasks below write every entry,
  // the blocks' padding past the image's edges included, so the pages (50 MB for 1080p) are
  // first touched by those tasks, in parallel, and written once.
  resizeOnHugePages(x_, n);
  resizeOnHugePages(y_, n);
  resizeOnHugePages(z_, n);
  resizeOnHugePages(valid_, n);
  const auto noRay = [&](size_t k) {
    x_[k] = 0.0, y_[k] = 0.0, z_[k] = 1.0;
    valid_[k] = 0;
  };
  const int paddedWidth = int(blocksPerRow_) * kBlock;
  // sensorDirection of every pixel centre, kBatch pixels of a row at a time (the lens solves
  // them side by side, with the same result).
  constexpr int kBatch = Lens::kBatch;
  parallelFor(blockRows * kBlock, 8, [&](size_t rowBegin, size_t rowEnd) {
    glm::dvec2 pixels[kBatch];
    glm::dvec3 dirs[kBatch];
    bool hasRay[kBatch];
    for (size_t i = rowBegin; i < rowEnd; ++i) {
      const int row = int(i);
      const int width = row < sensor_.height ? sensor_.width : 0;  // padding rows: no pixel
      for (int j0 = 0; j0 < width; j0 += kBatch) {
        const int count = std::min(kBatch, width - j0);
        for (int c = 0; c < count; ++c)
          pixels[c] =
              sourcePixelOfRaster(glm::dvec2(j0 + c + 0.5, double(i) + 0.5), sensor_.pixelCentre);
        sensor_.lens.unprojectBatch(count, pixels, dirs, hasRay);
        for (int c = 0; c < count; ++c) {
          const size_t k = index(row, j0 + c);
          if (!hasRay[c]) {
            noRay(k);
            continue;
          }
          x_[k] = dirs[c].x;
          y_[k] = dirs[c].y;
          z_[k] = dirs[c].z;
          valid_[k] = 1;
        }
      }
      for (int j = width; j < paddedWidth; ++j) noRay(index(row, j));
    }
  });
  boundPlaneCrossings(blockRows);
}

namespace {

/// `b` (x0, y0, x1, y1) as floats that hold it: the lows rounded down, the highs up.
glm::vec4 outwardToFloat(const glm::dvec4& b) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  const auto down = [&](double v) {
    const float f = float(v);
    return double(f) > v ? std::nextafter(f, -inf) : f;
  };
  const auto up = [&](double v) {
    const float f = float(v);
    return double(f) < v ? std::nextafter(f, inf) : f;
  };
  return glm::vec4(down(b.x), down(b.y), up(b.z), up(b.w));
}

/// The bounds (x0, y0, x1, y1) holding both `a` and `b`.
glm::dvec4 boundsUnion(const glm::dvec4& a, const glm::dvec4& b) {
  return glm::dvec4(std::min(a.x, b.x), std::min(a.y, b.y), std::max(a.z, b.z), std::max(a.w, b.w));
}

}  // namespace

void DirectionTable::boundPlaneCrossings(size_t blockRows) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  constexpr int kLanes = kBlock * kBlock;
  const glm::dvec4 none(inf, inf, -inf, -inf);
  planeBounds_.assign(blockRows * blocksPerRow_, glm::vec4(none));
  blockRays_.assign(planeBounds_.size(), 0);
  std::mutex mutex;
  planeExtent_ = none;
  parallelFor(planeBounds_.size(), 64, [&](size_t first, size_t last) {
    glm::dvec4 extent = none;
    double cosine = 1;
    for (size_t b = first; b < last; ++b) {
      glm::dvec4 bounds = none;
      uint16_t rays = 0;
      for (size_t k = b * kLanes; k < (b + 1) * kLanes; ++k) {
        if (!valid_[k]) continue;
        rays = uint16_t(rays | (1u << (k - b * kLanes)));
        cosine = std::min(cosine, z_[k]);
        if (!(z_[k] > 0)) continue;  // behind the plane: minCosine rules the table out
        const double px = x_[k] / z_[k], py = y_[k] / z_[k];
        bounds = boundsUnion(bounds, glm::dvec4(px, py, px, py));
      }
      planeBounds_[b] = outwardToFloat(bounds);
      blockRays_[b] = rays;
      extent = boundsUnion(extent, bounds);
    }
    const std::lock_guard<std::mutex> lock(mutex);
    planeExtent_ = boundsUnion(planeExtent_, extent);
    minCosine_ = std::min(minCosine_, cosine);
  });
}

size_t DirectionTable::validCount() const {
  return size_t(std::count(valid_.begin(), valid_.end(), 1));
}

size_t DirectionTable::bytesFor(int width, int height) {
  const size_t blocks =
      size_t((width + kBlock - 1) / kBlock) * size_t((height + kBlock - 1) / kBlock);
  // x, y, z and the validity byte per entry, kBlock² entries, the plane bounds and ray bits.
  constexpr size_t kEntries = kBlock * kBlock;
  return blocks * (kEntries * (3 * sizeof(double) + 1) + sizeof(glm::vec4) + sizeof(uint16_t));
}

size_t DirectionTable::peakBytes(const std::vector<CalibratedSensor>& sensors) {
  // Sensors as operator== compares them: size, pixel convention, model and parameters.
  std::set<std::vector<double>> distinct;
  size_t all = 0, largest = 0;
  for (const CalibratedSensor& s : sensors) {
    std::vector<double> key = {double(s.width), double(s.height), double(s.pixelCentre),
                               double(s.lens.model())};
    key.insert(key.end(), s.lens.params().begin(), s.lens.params().end());
    if (!distinct.insert(std::move(key)).second) continue;
    const size_t bytes = bytesFor(s.width, s.height);
    all += bytes;
    largest = std::max(largest, bytes);
  }
  return std::min(all, kCacheBytes + largest);
}

namespace {

/// The cache of DirectionTable::of. A batch renders image after image; images of one sensor
/// usually come together (COLMAP sorts by image id), so a few recent tables suffice. A 1080p
/// table holds 54 MB, a 24 Mpx DSLR's 630 MB: the cache keeps the most recent tables up to
/// 1 GiB (at least one).
struct TableCache {
  std::mutex mutex;
  std::list<std::shared_ptr<const DirectionTable>> recent;  // most recent first
};

TableCache& tableCache() {
  static TableCache cache;
  return cache;
}

}  // namespace

bool DirectionTable::cached(const CalibratedSensor& sensor) {
  TableCache& cache = tableCache();
  std::lock_guard<std::mutex> lock(cache.mutex);
  return std::any_of(cache.recent.begin(), cache.recent.end(),
                     [&](const auto& table) { return table->sensor() == sensor; });
}

std::shared_ptr<const DirectionTable> DirectionTable::of(const CalibratedSensor& sensor) {
  TableCache& cache = tableCache();
  std::lock_guard<std::mutex> lock(cache.mutex);
  std::list<std::shared_ptr<const DirectionTable>>& recent = cache.recent;
  for (auto it = recent.begin(); it != recent.end(); ++it)
    if ((*it)->sensor() == sensor) {
      recent.splice(recent.begin(), recent, it);
      return recent.front();
    }
  recent.push_front(std::make_shared<const DirectionTable>(sensor));
  size_t bytes = 0;
  for (auto it = recent.begin(); it != recent.end(); ++it) {
    bytes += (*it)->bytes();
    if (it != recent.begin() && bytes > kCacheBytes) {
      recent.erase(it, recent.end());
      break;
    }
  }
  return recent.front();
}

}  // namespace aperture
