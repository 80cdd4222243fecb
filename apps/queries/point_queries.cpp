#include "apps/queries/point_queries.h"

#include <algorithm>
#include <cstdint>
#include <sstream>

#include "core/queries/world_triangles.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture::app {

const std::vector<std::string>& pointQueryNames() {
  static const std::vector<std::string> names = {"closest", "distance", "sign", "occupancy"};
  return names;
}

PointQueryRequest parsePointQueries(const std::string& what, const std::string& flag) {
  PointQueryRequest r;
  std::stringstream items(what);
  std::string item;
  bool any = false;
  while (std::getline(items, item, ',')) {
    if (item == "closest")
      r.closest = true;
    else if (item == "distance")
      r.distance = true;
    else if (item == "sign")
      r.sign = true;
    else if (item == "occupancy")
      r.occupancy = true;
    else
      throw Error(cat(flag, ": unknown query '", item, "'", didYouMean(item, pointQueryNames()),
                      " (known: ", join(pointQueryNames(), ", "), ")"));
    any = true;
  }
  if (!any)
    throw Error(cat(flag, ": nothing to compute (known: ", join(pointQueryNames(), ", "), ")"));
  return r;
}

InsideOptions KeptInsideAnswers::prepare(const Scene& scene, InsideOptions options) {
  if (scene.stats().triangles == 0) return options;  // insideOf refuses it, naming why
  std::lock_guard<std::mutex> lock(mutex_);
  if (options.method == InsideMethod::Automatic && !options.closed) {
    if (!closed_) closed_ = checkClosed(scene);
    options.closed = &*closed_;
  }
  const bool winding =
      resolvedInsideMethod(options.method, options.closed && options.closed->closed) ==
      InsideMethod::Winding;
  if (winding && !options.windingTree) {
    if (!tree_) tree_ = std::make_unique<WindingNumberTree>(worldTriangleCorners(scene));
    options.windingTree = tree_.get();
  }
  return options;
}

void KeptInsideAnswers::forget() {
  std::lock_guard<std::mutex> lock(mutex_);
  closed_.reset();
  tree_.reset();
}

PointQueryResults runPointQueries(const Scene& scene, const double* points, size_t count,
                                  const PointQueryRequest& request) {
  PointQueryResults r;
  r.count = count;
  if (request.needsClosest()) {
    r.closest = closestPoints(scene, points, count);
    r.nonFinite = r.closest.nonFinite;
  }
  if (request.needsInside()) {
    r.inside = insideOf(scene, points, count, request.inside);
    r.nonFinite = std::max(r.nonFinite, r.inside.nonFinite);
  }
  if (request.sign) {
    r.signedDistance = r.closest.distance;
    for (size_t k = 0; k < count; ++k)
      if (r.inside.inside[k]) r.signedDistance[k] = -r.signedDistance[k];
  }
  return r;
}

namespace {

/// NumPy's dtype string of the element types the query arrays use.
const char* dtypeName(const double*) { return "<f8"; }
const char* dtypeName(const uint32_t*) { return "<u4"; }
const char* dtypeName(const uint8_t*) { return "|u1"; }

template <class T>
NpzArray arrayOf(const std::string& name, const std::vector<T>& v, std::vector<uint64_t> shape) {
  return {name, dtypeName(v.data()), std::move(shape), v.data(), v.size() * sizeof(T)};
}

}  // namespace

std::vector<NpzArray> pointQueryArrays(const PointQueryResults& r,
                                       const PointQueryRequest& request) {
  const uint64_t n = r.count;
  std::vector<NpzArray> out;
  if (request.closest) {
    out.push_back(arrayOf("points", r.closest.points, {n, 3}));
    out.push_back(arrayOf("primid", r.closest.primId, {n}));
    out.push_back(arrayOf("barycentric", r.closest.barycentric, {n, 3}));
    out.push_back(arrayOf("geomid", r.closest.geomId, {n}));
    out.push_back(arrayOf("instance", r.closest.instance, {n}));
  }
  if (request.distance) out.push_back(arrayOf("distance", r.closest.distance, {n}));
  if (request.sign) out.push_back(arrayOf("signed_distance", r.signedDistance, {n}));
  if (request.occupancy) out.push_back(arrayOf("occupancy", r.inside.inside, {n}));
  if (request.needsInside() && r.inside.method == InsideMethod::Winding)
    out.push_back(arrayOf("winding_number", r.inside.winding, {n}));
  return out;
}

std::string insideMethodOf(const PointQueryResults& r) { return insideMethodName(r.inside.method); }

}  // namespace aperture::app
