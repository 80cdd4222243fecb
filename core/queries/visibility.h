#pragma once
// Which faces and which points each camera sees (`aperture visibility`, Python
// Scene.face_visibility / point_visibility; docs/visibility.md).
//
// Faces are the triangles of the scene's one mesh (object 0), in the order it was loaded in
// (primID's; Mesh::sourceTriangles). Camera c
// sees face f when
//   1. f's centroid projects inside c's image, [0, W) x [0, H) in raster coordinates, through
//      Camera::project (the model's full forward map, only where its inverse is exact), and
//   2. the centre ray through that raster position (Camera::centreRayAt) hits f first;
//   3. with FaceVisibilityOptions::frontOnly, also dot(ray direction, n) < 0, n the normal of
//      the counter-clockwise winding (v1 − v0) × (v2 − v0).
// A face smaller than a pixel is seen by this definition. face pixels count the pixel-centre
// rays whose first hit is the face: exactly the primID renders of the frame loop, bincounted.
// The best view is the camera, among those that see f, with the largest projected area in
// pixels (ties: the lower camera index).
//
// Point p (world) is seen by camera c when p projects inside c's image (as 1.) and no surface
// lies on the centre ray from its origin o towards p closer than d·(1 − tolerance), d = |p − o|
// (Embree occlusion queries, rtcOccluded16).
#include <cstdint>
#include <functional>
#include <glm/glm.hpp>
#include <vector>

#include "core/engine/camera.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"

namespace aperture {

/// Compressed sparse rows, as scipy's CSR index arrays: row r holds
/// indices[indptr[r] .. indptr[r + 1]), ascending.
struct SparseRows {
  std::vector<uint64_t> indptr{0};  ///< rows() + 1 offsets, indptr[0] = 0
  std::vector<uint32_t> indices;
  size_t rows() const { return indptr.size() - 1; }
};

/// The transpose of `rows` whose indices lie in [0, columns): row c of the result lists the
/// rows of `rows` that hold c, ascending. Throws Error for an index >= columns.
SparseRows transposeRows(const SparseRows& rows, size_t columns);

/// Which centre rays faceVisibility traces (docs/visibility.md, "Speed"). Both give the same
/// arrays; `all` is the reference `needed` is tested against.
enum class FaceRays {
  /// Only the rays whose hit can change the answer: with frontOnly, a face the ray meets from
  /// its back is not seen whatever the ray hits, so its ray is not traced.
  needed,
  /// One ray per face whose centroid projects inside the image (the definition, traced).
  all,
};

struct FaceVisibilityOptions {
  bool frontOnly = false;            ///< count a camera only on the side the CCW winding faces
  FaceRays rays = FaceRays::needed;  ///< which centre rays are traced (the same result)
  /// Packet width and tile size of the primID renders that count face pixels (the frame
  /// loop's; spp and the normal frame do not matter to primID from the centre ray).
  RenderSettings render;
  /// Called after each camera with (cameras done, cameras), from the calling thread.
  std::function<void(size_t, size_t)> progress;
};

struct FaceVisibility {
  std::vector<uint32_t> viewCount;  ///< per face: how many cameras see it
  std::vector<uint64_t> pixels;     ///< per face: pixel-centre rays, all cameras, hitting it first
  std::vector<int32_t> bestView;    ///< per face: camera with the largest projected area, or −1
  SparseRows cameraFaces;           ///< per camera: the faces it sees
  SparseRows faceCameras;           ///< per face: the cameras that see it
};

/// Face visibility of `cameras` (built with the scene's render origin) over the scene's one
/// mesh. Throws Error naming the reason when the scene is not one mesh placed once,
/// untransformed and unculled, or a camera's spp differs from what renderImage accepts.
FaceVisibility faceVisibility(const Scene& scene, const std::vector<const Camera*>& cameras,
                              const FaceVisibilityOptions& options = {});

/// Area in pixels of the triangle of world points `a`, `b`, `c` as `camera` images it: the
/// triangle of their projections. Where a corner has no projection, the triangle shrunk
/// towards its centroid by halves until all three project, its area scaled back by 4 per
/// halving (0 when the centroid itself has none).
double projectedAreaPixels(const Camera& camera, const glm::dvec3& a, const glm::dvec3& b,
                           const glm::dvec3& c);

struct PointVisibilityOptions {
  double tolerance = 0.01;  ///< --occlusion-tolerance: occluders count closer than d·(1 − tol)
  /// Called after each camera with (cameras done, cameras), from the calling thread.
  std::function<void(size_t, size_t)> progress;
};

struct PointVisibility {
  SparseRows pointCameras;  ///< per point: the cameras that see it
  SparseRows cameraPoints;  ///< per camera: the points it sees (the transpose)
};

/// Point visibility of world points `points` in `cameras`. Throws Error for a tolerance outside
/// [0, 1) or a non-finite point (naming its index).
PointVisibility pointVisibility(const Scene& scene, const std::vector<const Camera*>& cameras,
                                const std::vector<glm::dvec3>& points,
                                const PointVisibilityOptions& options = {});

/// One observation of a point in a camera (a COLMAP track element, the camera an index into
/// the cameras given).
struct PointObservation {
  uint32_t point = 0;
  uint32_t camera = 0;
};

/// How a camera sees observations: seen; projected inside the image but occluded by the mesh;
/// outside the image (no projection, or outside [0, W) x [0, H)).
struct ObservationCounts {
  uint64_t seen = 0, occluded = 0, outside = 0;
};

/// Classifies each observation as pointVisibility would (same tolerance) and counts them: the
/// number of track observations the mesh occludes, which users clean reconstructions with.
ObservationCounts classifyObservations(const Scene& scene,
                                       const std::vector<const Camera*>& cameras,
                                       const std::vector<glm::dvec3>& points,
                                       const std::vector<PointObservation>& observations,
                                       double tolerance);

}  // namespace aperture
