#include "query_binding.h"

#include <nanobind/stl/string.h>

#include <memory>
#include <vector>

#include "apps/queries/point_queries.h"
#include "bindings.h"
#include "core/queries/ray_hits.h"
#include "core/util/error.h"
#include "named_arrays.h"

namespace aperture::python {

namespace {

void checkSameCount(const Points& origins, const Points& directions, const char* what) {
  if (origins.shape(0) != directions.shape(0))
    throw nb::value_error(
        cat(what, ": origins has ", origins.shape(0), " rows, directions ", directions.shape(0))
            .c_str());
}

}  // namespace

nb::tuple pointQueries(const Scene& scene, app::KeptInsideAnswers& kept, const Points& points,
                       const std::string& what, const std::string& method, int parityDirections,
                       int threads) {
  app::PointQueryRequest request = app::parsePointQueries(what, "what");
  request.inside.method = parseInsideMethod(method);
  request.inside.parityDirections = parityDirections;
  auto r = std::make_shared<app::PointQueryResults>();
  const size_t n = points.shape(0);
  withoutGil(threads, [&] {
    if (request.needsInside()) request.inside = kept.prepare(scene, request.inside);
    *r = app::runPointQueries(scene, points.data(), n, request);
  });
  const std::string used = request.needsInside() ? app::insideMethodOf(*r) : std::string();
  nb::dict arrays = namedArrays(r, app::pointQueryArrays(*r, request));
  return nb::make_tuple(arrays, r->nonFinite, used);
}

nb::tuple countIntersections(const Scene& scene, const Points& origins, const Points& directions,
                             int threads) {
  checkSameCount(origins, directions, "count_intersections");
  auto counts = std::make_shared<std::vector<uint32_t>>();
  size_t nonFinite = 0;
  withoutGil(threads, [&] {
    *counts = aperture::countIntersections(scene, origins.data(), directions.data(),
                                           origins.shape(0), &nonFinite);
  });
  const NpzArray a{"counts", "<u4", {counts->size()}, counts->data(), counts->size() * 4};
  const nb::object array = namedArrays(counts, {a})["counts"];
  return nb::make_tuple(array, nonFinite);
}

nb::tuple listIntersections(const Scene& scene, const Points& origins, const Points& directions,
                            int threads) {
  checkSameCount(origins, directions, "list_intersections");
  struct Lists {
    RayHitList hits;
    std::vector<uint32_t> rayIds;
  };
  auto l = std::make_shared<Lists>();
  withoutGil(threads, [&] {
    l->hits =
        aperture::listIntersections(scene, origins.data(), directions.data(), origins.shape(0));
    l->rayIds.resize(l->hits.t.size());
    for (size_t k = 0; k + 1 < l->hits.offsets.size(); ++k)
      for (uint64_t h = l->hits.offsets[k]; h < l->hits.offsets[k + 1]; ++h)
        l->rayIds[h] = uint32_t(k);
  });
  const RayHitList& h = l->hits;
  const std::vector<NpzArray> arrays = {
      {"ray_splits", "<u8", {h.offsets.size()}, h.offsets.data(), h.offsets.size() * 8},
      {"ray_ids", "<u4", {l->rayIds.size()}, l->rayIds.data(), l->rayIds.size() * 4},
      {"t", "<f8", {h.t.size()}, h.t.data(), h.t.size() * 8},
      {"primid", "<u4", {h.primId.size()}, h.primId.data(), h.primId.size() * 4},
      {"geomid", "<u4", {h.geomId.size()}, h.geomId.data(), h.geomId.size() * 4}};
  return nb::make_tuple(namedArrays(l, arrays), h.nonFinite);
}

}  // namespace aperture::python
