#pragma once
// Point and ray queries on aperture.Scene (apps/queries/point_queries.h,
// core/queries/ray_hits.h): closest points, signed distance, occupancy, intersection counts
// and lists, NumPy in and out, the GIL released. Bound on the scene class through
// bindSceneQueries, which only needs the class to give its built Scene.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <optional>
#include <string>

#include "apps/queries/point_queries.h"
#include "core/engine/scene.h"

namespace aperture::python {

namespace nb = nanobind;

/// (N, 3) float64, C order: what the Python side hands over (it converts float32).
using Points = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;

/// (dict of arrays, non-finite count, method name or "") for `what`
/// ("closest,distance,sign,occupancy" items), `method` "automatic", "parity" or "winding";
/// the closedness check and winding tree are taken from (and made into) `kept`.
nb::tuple pointQueries(const Scene& scene, app::KeptInsideAnswers& kept, const Points& points,
                       const std::string& what, const std::string& method, int parityDirections,
                       int threads);
/// (counts (N) uint32, non-finite count).
nb::tuple countIntersections(const Scene& scene, const Points& origins, const Points& directions,
                             int threads);
/// (dict ray_splits, ray_ids, t, primid, geomid, non-finite count).
nb::tuple listIntersections(const Scene& scene, const Points& origins, const Points& directions,
                            int threads);

/// The query methods of `c`, whose instances give their Scene by `scene()` and what the sign
/// keeps of it by `keptInsideAnswers()`.
template <class PyScene>
void bindSceneQueries(nb::class_<PyScene>& c) {
  c.def(
       "_point_queries",
       [](const PyScene& s, const Points& points, const std::string& what,
          const std::string& method, int parityDirections, int threads) {
         return pointQueries(s.scene(), s.keptInsideAnswers(), points, what, method,
                             parityDirections, threads);
       },
       nb::arg("points"), nb::arg("what"), nb::arg("method"), nb::arg("parity_directions"),
       nb::arg("threads"))
      .def(
          "_count_intersections",
          [](const PyScene& s, const Points& origins, const Points& directions, int threads) {
            return countIntersections(s.scene(), origins, directions, threads);
          },
          nb::arg("origins"), nb::arg("directions"), nb::arg("threads"))
      .def(
          "_list_intersections",
          [](const PyScene& s, const Points& origins, const Points& directions, int threads) {
            return listIntersections(s.scene(), origins, directions, threads);
          },
          nb::arg("origins"), nb::arg("directions"), nb::arg("threads"));
}

}  // namespace aperture::python
