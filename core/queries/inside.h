#pragma once
// Inside or outside of a scene's surface: the sign of a signed distance and occupancy
// (issue 44; docs/queries.md, "Sign and occupancy"). Two methods, and the one that ran is always
// reported:
//  - parity: the number of surface crossings along a ray from the point, odd = inside; the
//    majority over parityDirections fixed directions (parityDirection). Each crossing is
//    counted once by retracing from the next float past each hit (Embree's closest hit, through
//    intersectScene) or, on a scene built with BuildOptions::contextFilter, in one traversal
//    whose filter collects every hit, walked in order of t as the retrace meets them (the same
//    answers: docs/queries.md, "Sign and occupancy"); a ray whose hit is ambiguous is not counted
//    at all but replaced by the next fixed direction: a hit within a few float ulps of an edge or a
//    vertex (where Embree's robust test may report both triangles of an edge, at the same t or one
//    float apart, or a silhouette's two triangles at one t, which the retrace would count once), a
//    grazing hit, or one at the ray's own origin. A point outside the scene's box is outside
//    without a ray (nothing can enclose it), so every ray starts within a box diagonal of the
//    surface and Embree's rounding (relative to the distance from the origin) stays at the scene's
//    scale. Needs the scene built robust (BuildOptions::robust, the default): without it a ray can
//    slip between two triangles of an edge without any hit to tell.
//  - winding: the generalized winding number (Jacobson, Kavan and Sorkine-Hornung 2013),
//    inside when w > 0.5, evaluated through a hierarchy of far-field terms with a documented
//    error bound (winding_number.h), exactly below a threshold of triangles.
// The default (InsideMethod::Automatic) is parity for a closed scene (checkClosed) and winding
// otherwise. Points on the surface: parity's every ray starts on it, so it is counted
// undecided and reported outside (inside = 0); the winding number there is about 0.5 (either
// side). Every answer depends on its point alone: the same in any batch and thread count.
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "core/engine/scene.h"

namespace aperture {

class WindingNumberTree;

enum class InsideMethod { Automatic, Parity, Winding };

/// "parity", "winding" or "automatic"; parseInsideMethod throws Error naming the bad value,
/// with "did you mean".
const char* insideMethodName(InsideMethod method);
InsideMethod parseInsideMethod(const std::string& name);
/// The method insideOf runs when asked for `asked` on a scene that is `closed` (checkClosed):
/// `asked`, or for Automatic parity when closed and winding otherwise.
InsideMethod resolvedInsideMethod(InsideMethod asked, bool closed);

/// Whether the scene's surface is closed: every edge of every object (edges by vertex
/// position in world space, double, so that split vertices of a PLY or glTF still join) is
/// shared by exactly two triangles that traverse it in opposite directions. Triangles with two
/// corners at one position are left out. Parallel sorts of the welded vertices and the edges.
struct ClosedCheck {
  bool closed = false;
  size_t edges = 0;             ///< distinct edges
  size_t boundaryEdges = 0;     ///< used by one triangle
  size_t nonManifoldEdges = 0;  ///< used by more than two
  size_t misorientedEdges = 0;  ///< used by two triangles in the same direction
};
ClosedCheck checkClosed(const Scene& scene);

/// Parity's fixed directions: kParityDirectionCount unit vectors spread over the sphere (a
/// spherical Fibonacci set with irrational offsets, none along an axis or in a coordinate
/// plane), taken in order. A ray that meets the surface ambiguously (InsideResult::discardedRays)
/// is replaced by the next one.
inline constexpr int kParityDirectionCount = 32;
/// The largest InsideOptions::parityDirections.
inline constexpr int kMaxParityDirections = 15;
/// Throws Error ("NAME D must be odd, in [1, 15]") unless `directions` is a parity vote
/// InsideOptions takes; `name` is how the caller's user gave it.
void checkParityDirections(int directions, const char* name);
/// Direction k (0 <= k < kParityDirectionCount) as traced (float, unit length).
glm::vec3 parityDirection(int k);

struct InsideOptions {
  InsideMethod method = InsideMethod::Automatic;
  /// Parity: the number of fixed directions voted over (1, 3, 5, ...; odd). Tracing stops
  /// once one side holds a majority of them (3 of 5 agreeing: the other 2 are not traced).
  int parityDirections = 1;
  /// Winding: the far-field accuracy parameter (a cluster is expanded when the point is
  /// closer than `windingBeta` times its radius); the error bound it gives is documented in
  /// winding_number.h.
  double windingBeta = 2.0;
  /// Automatic: checkClosed(scene), when the caller keeps it (a scene queried many times:
  /// the check sorts every edge, 0.3 s for the dragon); null: insideOf runs it.
  const ClosedCheck* closed = nullptr;
  /// Winding: a tree over worldTriangleCorners(scene) the caller keeps (winding_number.h);
  /// null: insideOf builds one for the call.
  const WindingNumberTree* windingTree = nullptr;
};

/// Per point: inside (1) or not (0), and for the winding method the winding number itself.
/// Points that are not finite get inside = 0, winding = NaN and are counted in nonFinite.
struct InsideResult {
  InsideMethod method = InsideMethod::Parity;  ///< the method that ran (never Automatic)
  std::vector<uint8_t> inside;
  std::vector<double> winding;  ///< empty unless method == Winding
  /// Winding: the bound on each point's truncation error (winding_number.h); 0 where the
  /// sum was exact, NaN where the point is not finite. Empty unless method == Winding.
  std::vector<double> windingErrorBound;
  size_t nonFinite = 0;
  /// Parity: rays replaced by the next fixed direction because they met the surface where
  /// a crossing cannot be counted with certainty: closer to an edge or a vertex than
  /// kParityEdgeTolerance · (t + L) (t the hit's distance, L the scene box's diagonal), at a
  /// grazing angle (|cos| < kParityGrazingCosine), or closer to their origin than
  /// kParitySurfaceBand · L.
  size_t discardedRays = 0;
  /// Parity: points for which every fixed direction was discarded: points on the surface,
  /// whose every ray starts on it. They get inside = 0.
  size_t undecided = 0;
};

/// Parity's thresholds of an ambiguous hit (InsideResult::discardedRays).
inline constexpr float kParityEdgeTolerance = 1e-6f;
inline constexpr float kParityGrazingCosine = 1e-5f;
inline constexpr float kParitySurfaceBand = 1e-6f;

/// `points` holds 3 * count world coordinates (x, y, z per point). Every core is used; throws
/// Error for an empty scene.
InsideResult insideOf(const Scene& scene, const double* points, size_t count,
                      const InsideOptions& options = {});

}  // namespace aperture
