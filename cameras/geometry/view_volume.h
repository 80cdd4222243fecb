#pragma once
// The view volume of a camera: the part of space its rays reach between a near and a far
// distance. Used by --describe and, later, to cull geometry no camera can see.
#include <array>
#include <glm/glm.hpp>
#include <string>
#include <vector>

namespace aperture {

/// A world-space plane; the inside is dot(normal, p) <= offset. normal is unit length.
struct Plane {
  glm::dvec3 normal{0.0, 0.0, 1.0};
  double offset = 0;
  double eyeOffset = 0;  ///< the same plane relative to the eye: dot(normal, p − e) <= eyeOffset
};

/// The view volume of one camera.
///
/// Planar cameras (perspective, thin lens, orthographic, oblique) use camera coordinates
/// x = (p − e)·U, y = (p − e)·V and depth z = (p − e)·(−W) (the same depth as the Z AOV).
/// Their volume is { nearDist <= z <= farDist, xLo(z) <= x <= xHi(z), yLo(z) <= y <= yHi(z) }
/// with each bound linear in z (Linear): constant for the orthographic box, sheared for the
/// oblique parallelepiped, through the eye for the (possibly off-axis) perspective frustum,
/// and for the thin lens a sheared frustum that contains every ray from the lens disk
/// through the in-focus window (conservative: the disk is bounded by its square). Near and
/// far are depths along −W, not distances along the ray.
///
/// Panoramas (equirect, fisheye) have kind AllSpace: the shell nearDist <= |p − e| <= farDist
/// (distances from the eye), which contains what they see (exactly for a full sphere).
struct ViewVolume {
  enum class Kind { Box, Parallelepiped, Frustum, ShearedFrustum, AllSpace };
  /// b·z + a, a bound in camera coordinates as a function of the depth z.
  struct Linear {
    double a = 0, b = 0;
    double at(double z) const { return a + b * z; }
  };

  Kind kind = Kind::AllSpace;
  double nearDist = 0, farDist = 0;  ///< depth (planar kinds) or distance (AllSpace)
  glm::dvec3 eye{0.0}, u{1, 0, 0}, v{0, 1, 0}, w{0, 0, 1};  ///< the camera frame, world
  Linear xLo, xHi, yLo, yHi;                                ///< planar kinds only
  /// World-space corners: the near cross-section (xLo,yLo), (xHi,yLo), (xHi,yHi), (xLo,yHi),
  /// then the far one in the same order. AllSpace: the cube around the far sphere. Corners
  /// at an infinite far distance are not finite.
  std::array<glm::dvec3, 8> corners{};
  /// Bounding planes (inside = all satisfied): x and y bounds, near, and far when finite.
  /// Empty for AllSpace.
  std::vector<Plane> planes;

  /// True when the world point lies in the volume (exact test, no tolerance).
  bool contains(const glm::dvec3& worldPoint) const;
  /// Conservative: false only when the box [lo, hi] is certainly outside the volume, with a
  /// relative slack of 1e-6 so rays rounded to float still count. Never false for a box a
  /// camera ray hits at a depth (distance for AllSpace) within [nearDist, farDist].
  bool mayIntersectBox(const glm::dvec3& lo, const glm::dvec3& hi) const;
  /// "box", "parallelepiped", "frustum", "sheared frustum", "all space".
  std::string kindName() const;

  /// Builds a planar volume: fills corners and planes from the bounds. Throws Error unless
  /// 0 <= nearDist <= farDist (farDist may be +inf).
  static ViewVolume planar(Kind kind, const glm::dvec3& eye, const glm::dvec3& u,
                           const glm::dvec3& v, const glm::dvec3& w, double nearDist,
                           double farDist, Linear xLo, Linear xHi, Linear yLo, Linear yHi);
  /// The AllSpace shell around eye.
  static ViewVolume allSpace(const glm::dvec3& eye, const glm::dvec3& u, const glm::dvec3& v,
                             const glm::dvec3& w, double nearDist, double farDist);
};

}  // namespace aperture
