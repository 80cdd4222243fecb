#include "cameras/geometry/view_volume.h"

#include <cmath>
#include <limits>

#include "core/util/error.h"

namespace aperture {

namespace {

void checkRange(double nearDist, double farDist) {
  if (!(std::isfinite(nearDist) && nearDist >= 0 && farDist >= nearDist && !std::isnan(farDist)))
    throw Error(cat("view volume: need 0 <= near <= far (far may be +inf), got near ", nearDist,
                    ", far ", farDist));
}

// Plane relative to the eye: dot(n, p − e) <= c  ->  world offset c + dot(n, e).
Plane worldPlane(const glm::dvec3& n, double c, const glm::dvec3& eye) {
  const double len = glm::length(n);
  return {n / len, c / len + glm::dot(n / len, eye), c / len};
}

/// A view volume of `kind` with the camera frame (eye, U, V, W) and the checked depth range:
/// what both kinds hold before their corners and planes.
ViewVolume framedVolume(ViewVolume::Kind kind, const glm::dvec3& eye, const glm::dvec3& u,
                        const glm::dvec3& v, const glm::dvec3& w, double nearDist, double farDist) {
  checkRange(nearDist, farDist);
  ViewVolume vv;
  vv.kind = kind;
  vv.nearDist = nearDist;
  vv.farDist = farDist;
  vv.eye = eye;
  vv.u = u;
  vv.v = v;
  vv.w = w;
  return vv;
}

}  // namespace

ViewVolume ViewVolume::planar(Kind kind, const glm::dvec3& eye, const glm::dvec3& u,
                              const glm::dvec3& v, const glm::dvec3& w, double nearDist,
                              double farDist, Linear xLo, Linear xHi, Linear yLo, Linear yHi) {
  ViewVolume vv = framedVolume(kind, eye, u, v, w, nearDist, farDist);
  vv.xLo = xLo;
  vv.xHi = xHi;
  vv.yLo = yLo;
  vv.yHi = yHi;
  const double inf = std::numeric_limits<double>::infinity();
  for (int layer = 0; layer < 2; ++layer) {
    const double z = layer == 0 ? nearDist : farDist;
    const double xs[4] = {xLo.at(z), xHi.at(z), xHi.at(z), xLo.at(z)};
    const double ys[4] = {yLo.at(z), yLo.at(z), yHi.at(z), yHi.at(z)};
    for (int c = 0; c < 4; ++c)
      vv.corners[4 * layer + c] =
          std::isfinite(z) ? eye + xs[c] * u + ys[c] * v - z * w : glm::dvec3(inf);
  }
  // x <= a + b z  <=>  dot(U + b W, p − e) <= a   (z = −dot(W, p − e)); likewise for the rest.
  vv.planes.push_back(worldPlane(u + xHi.b * w, xHi.a, eye));
  vv.planes.push_back(worldPlane(-u - xLo.b * w, -xLo.a, eye));
  vv.planes.push_back(worldPlane(v + yHi.b * w, yHi.a, eye));
  vv.planes.push_back(worldPlane(-v - yLo.b * w, -yLo.a, eye));
  vv.planes.push_back(worldPlane(w, -nearDist, eye));
  if (std::isfinite(farDist)) vv.planes.push_back(worldPlane(-w, farDist, eye));
  return vv;
}

ViewVolume ViewVolume::allSpace(const glm::dvec3& eye, const glm::dvec3& u, const glm::dvec3& v,
                                const glm::dvec3& w, double nearDist, double farDist) {
  ViewVolume vv = framedVolume(Kind::AllSpace, eye, u, v, w, nearDist, farDist);
  for (int c = 0; c < 8; ++c) {
    const double sx = (c == 1 || c == 2 || c == 5 || c == 6) ? 1 : -1;
    const double sy = (c % 4 >= 2) ? 1 : -1;
    const double sz = c < 4 ? 1 : -1;
    vv.corners[c] = eye + farDist * (sx * u + sy * v + sz * w);
  }
  return vv;
}

bool ViewVolume::contains(const glm::dvec3& worldPoint) const {
  const glm::dvec3 p = worldPoint - eye;
  if (kind == Kind::AllSpace) {
    const double r = glm::length(p);
    return r >= nearDist && r <= farDist;
  }
  const double x = glm::dot(p, u), y = glm::dot(p, v), z = -glm::dot(p, w);
  return z >= nearDist && z <= farDist && x >= xLo.at(z) && x <= xHi.at(z) && y >= yLo.at(z) &&
         y <= yHi.at(z);
}

bool ViewVolume::mayIntersectBox(const glm::dvec3& lo, const glm::dvec3& hi) const {
  const glm::dvec3 centre = 0.5 * (lo + hi) - eye, half = 0.5 * (hi - lo);
  const double slackRel = 1e-6;
  if (kind == Kind::AllSpace) {
    // Distance range from the eye to the box.
    const glm::dvec3 nearest = glm::max(glm::abs(centre) - half, glm::dvec3(0.0));
    const double dMin = glm::length(nearest);
    const double dMax = glm::length(glm::abs(centre) + half);
    const double slack = slackRel * dMax;
    return dMin <= farDist + slack && dMax >= nearDist - slack;
  }
  for (const Plane& pl : planes) {
    // Eye-relative: the smallest dot(n, p − e) over the box against offset − dot(n, e).
    const double c = pl.eyeOffset;
    const double reach = glm::dot(glm::abs(pl.normal), half);
    const double minDot = glm::dot(pl.normal, centre) - reach;
    const double slack = slackRel * (std::abs(c) + std::abs(glm::dot(pl.normal, centre)) + reach);
    if (minDot > c + slack) return false;
  }
  return true;
}

std::string ViewVolume::kindName() const {
  switch (kind) {
    case Kind::Box:
      return "box";
    case Kind::Parallelepiped:
      return "parallelepiped";
    case Kind::Frustum:
      return "frustum";
    case Kind::ShearedFrustum:
      return "sheared frustum";
    case Kind::AllSpace:
      return "all space";
  }
  return "?";
}

}  // namespace aperture
