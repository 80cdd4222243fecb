#pragma once
// Point queries as `aperture query` and Python's Scene.closest_points / distance /
// signed_distance / occupancy run them (docs/queries.md): what to compute (--what), the
// computation (closest points from core/queries/closest_points.h, the sign from
// core/queries/inside.h) and the arrays it gives, under the one set of names the .npz and
// Python share.
#include <cstddef>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/engine/scene.h"
#include "core/io/npz.h"
#include "core/queries/closest_points.h"
#include "core/queries/inside.h"
#include "core/queries/winding_number.h"

namespace aperture::app {

/// What to compute for each point (--what closest,distance,sign,occupancy).
struct PointQueryRequest {
  bool closest = false;    ///< closest point, primid, barycentric, geomid, instance
  bool distance = false;   ///< unsigned distance
  bool sign = false;       ///< signed distance: negative inside
  bool occupancy = false;  ///< 1 inside, 0 outside
  InsideOptions inside;    ///< how sign and occupancy decide inside

  bool needsInside() const { return sign || occupancy; }
  bool needsClosest() const { return closest || distance || sign; }
};

/// "closest,distance,sign,occupancy" (any non-empty subset, comma-separated); Error naming
/// `flag` and the unknown item, with "did you mean".
PointQueryRequest parsePointQueries(const std::string& what, const std::string& flag);
/// The items parsePointQueries knows.
const std::vector<std::string>& pointQueryNames();

struct PointQueryResults {
  size_t count = 0;
  ClosestPoints closest;               ///< filled when needsClosest()
  std::vector<double> signedDistance;  ///< filled when sign
  InsideResult inside;                 ///< filled when needsInside()
  size_t nonFinite = 0;                ///< points that got NaN (or 0 occupancy)
};

/// What insideOf derives from a scene alone, kept across the queries of one scene (Python's
/// Scene): the closedness check (run when the method is automatic) and the winding tree (built
/// when winding runs, ~150 bytes a triangle), each made at the first query that needs it.
/// Thread-safe; forget() before the scene it was made from changes.
class KeptInsideAnswers {
 public:
  /// `options` with InsideOptions::closed and windingTree pointing at what is kept, made now
  /// when this call needs it and nothing is kept yet.
  InsideOptions prepare(const Scene& scene, InsideOptions options);
  void forget();

 private:
  std::mutex mutex_;
  std::optional<ClosedCheck> closed_;
  std::unique_ptr<WindingNumberTree> tree_;
};

/// Runs `request` on the `count` world points (x, y, z each) on every core.
PointQueryResults runPointQueries(const Scene& scene, const double* points, size_t count,
                                  const PointQueryRequest& request);

/// The arrays of `r` (pointing into it, which must outlive them): closest → points (N, 3)
/// float64, primid, geomid, instance (N) uint32, barycentric (N, 3) float64; distance →
/// distance (N) float64; sign → signed_distance (N) float64; occupancy → occupancy (N) uint8;
/// the winding method adds winding_number (N) float64.
std::vector<NpzArray> pointQueryArrays(const PointQueryResults& r,
                                       const PointQueryRequest& request);

/// The name of the method that decided inside ("parity" or "winding"), for sign_method.
std::string insideMethodOf(const PointQueryResults& r);

}  // namespace aperture::app
