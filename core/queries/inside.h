#pragma once
// Inside or outside of a scene's surface: the sign of a signed distance and occupancy
// (issue 44). Two methods, and the one that ran is always reported:
//  - parity: the number of surface crossings along a ray from the point, each crossing counted
//    once (Embree's watertight traversal: a ray through an edge or a vertex reports one of the
//    triangles that share it), odd = inside; optionally the majority over several fixed
//    directions;
//  - winding: the generalized winding number (Jacobson, Kavan and Sorkine-Hornung 2013),
//    inside when w > 0.5, evaluated through a hierarchy of far-field terms with a documented
//    error bound, exactly below a threshold of triangles.
// The default (InsideMethod::Automatic) is parity for a closed scene (checkClosed) and winding
// otherwise.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/engine/scene.h"

namespace aperture {

enum class InsideMethod { Automatic, Parity, Winding };

/// "parity", "winding" or "automatic"; parseInsideMethod throws Error naming the bad value,
/// with "did you mean".
const char* insideMethodName(InsideMethod method);
InsideMethod parseInsideMethod(const std::string& name);

/// Whether the scene's surface is closed: every edge of every object (edges by vertex
/// position, so that split vertices of a PLY or glTF still join) is shared by exactly two
/// triangles that traverse it in opposite directions.
struct ClosedCheck {
  bool closed = false;
  size_t edges = 0;             ///< distinct edges
  size_t boundaryEdges = 0;     ///< used by one triangle
  size_t nonManifoldEdges = 0;  ///< used by more than two
  size_t misorientedEdges = 0;  ///< used by two triangles in the same direction
};
ClosedCheck checkClosed(const Scene& scene);

struct InsideOptions {
  InsideMethod method = InsideMethod::Automatic;
  /// Parity: the number of fixed directions voted over (1, 3, 5, ...; odd).
  int parityDirections = 1;
  /// Winding: the far-field accuracy parameter (a cluster is expanded when the point is
  /// closer than `windingBeta` times its radius); the error bound it gives is documented in
  /// winding_number.h.
  double windingBeta = 2.0;
};

/// Per point: inside (1) or not (0), and for the winding method the winding number itself.
/// Points that are not finite get inside = 0, winding = NaN and are counted in nonFinite.
struct InsideResult {
  InsideMethod method = InsideMethod::Parity;  ///< the method that ran (never Automatic)
  std::vector<uint8_t> inside;
  std::vector<double> winding;  ///< empty unless method == Winding
  size_t nonFinite = 0;
};

/// `points` holds 3 * count world coordinates (x, y, z per point). Every core is used; throws
/// Error for an empty scene.
InsideResult insideOf(const Scene& scene, const double* points, size_t count,
                      const InsideOptions& options = {});

}  // namespace aperture
