// The exact inverse of the lens models (cameras/lenses/lens_inverse.h), written once over a number
// type T: a double for one point, Lanes (eight doubles) for eight side by side. A lane's
// branches are masks and selects, so every lane computes exactly its own operations whatever
// its neighbours do; masks are 0 or −1 (all bits) per lane for both types.
// The eight-double vectors here are passed and returned by value between this file's own
// inline functions only (all inlined into the kernels; none crosses the file), so GCC's note
// that their calling convention differs with and without AVX-512 concerns nothing here.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "cameras/lenses/lens_inverse.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/util/vector_kernel.h"

namespace aperture {
namespace {

// Newton's method on the 2D map (models with tangential or thin-prism terms). Residuals are in
// normalised coordinates, relative to max(1, |distorted|): iterations stop at 1e-15 (the
// rounding floor of the forward map) or when the step stalls at rounding; a solution is
// accepted up to 1e-12 (1e-6 px at a focal length of 1e6 px). From the radial inverse it takes
// three or four steps; 20 is far beyond what convergence needs away from a fold. A step that
// leaves the fold or raises the residual is halved, at most 40 times.
constexpr int kMaxNewtonIterations = 20;
constexpr int kMaxHalvings = 40;
constexpr double kConvergedResidual = 1e-15;
constexpr double kAcceptedResidual = 1e-12;
constexpr double kStalledStep = 1e-15;
// The radial profile's inverse: Newton's method inside a bracket (bisection when a step leaves
// it) from the table's first guess (good to ~1e-9: one step then reaches rounding).
constexpr int kMaxRadialIterations = 100;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxDouble = std::numeric_limits<double>::max();

// ---- The two number types and their masks.

/// Eight doubles, one per pixel (GCC's vector extension: one AVX-512 register).
using Lanes = double __attribute__((vector_size(kLensLanes * sizeof(double))));
/// Eight lane masks (0 or −1), the type Lanes comparisons give.
using LaneMasks = int64_t __attribute__((vector_size(kLensLanes * sizeof(int64_t))));

template <class T>
struct MaskTypeOf {
  using type = int64_t;  // a double's mask: 0 or −1, like one lane of LaneMasks
};
template <>
struct MaskTypeOf<Lanes> {
  using type = LaneMasks;
};
template <class T>
using MaskOf = typename MaskTypeOf<T>::type;

template <class T>
constexpr int kWidthOf = 1;
template <>
constexpr int kWidthOf<Lanes> = kLensLanes;

/// A comparison's result as a mask (a Lanes comparison already is one).
inline int64_t maskOf(bool b) { return -int64_t(b); }
inline LaneMasks maskOf(LaneMasks m) { return m; }
template <class M>
inline M allOf(bool b) {
  return b ? ~M{} : M{};
}

inline double select(int64_t m, double a, double b) { return m ? a : b; }
inline int64_t select(int64_t m, int64_t a, int64_t b) { return m ? a : b; }
inline Lanes select(LaneMasks m, Lanes a, Lanes b) { return m ? a : b; }
inline LaneMasks select(LaneMasks m, LaneMasks a, LaneMasks b) { return m ? a : b; }

inline bool any(int64_t m) { return m != 0; }
inline bool any(LaneMasks m) {
  int64_t lanes[kLensLanes], a = 0;
  std::memcpy(lanes, &m, sizeof m);
  for (int k = 0; k < kLensLanes; ++k) a |= lanes[k];
  return a != 0;
}

template <class T>
inline T splat(double c);
template <>
inline double splat<double>(double c) {
  return c;
}
template <>
inline Lanes splat<Lanes>(double c) {
  Lanes v;
  for (int k = 0; k < kLensLanes; ++k) v[k] = c;
  return v;
}

inline double sqrtOf(double x) { return std::sqrt(x); }
inline Lanes sqrtOf(Lanes x) {
  for (int k = 0; k < kLensLanes; ++k) x[k] = std::sqrt(x[k]);  // one vector √
  return x;
}
inline double absOf(double x) { return std::abs(x); }
inline Lanes absOf(Lanes x) {
  for (int k = 0; k < kLensLanes; ++k) x[k] = std::abs(x[k]);
  return x;
}

// Lane k of a value or mask, read and written (the per-lane fallbacks and the I/O).
inline double get(double x, int) { return x; }
inline double get(const Lanes& x, int k) { return x[k]; }
inline void set(double& x, int, double v) { x = v; }
inline void set(Lanes& x, int k, double v) { x[k] = v; }
inline bool isSet(int64_t m, int) { return m != 0; }
inline bool isSet(const LaneMasks& m, int k) { return m[k] != 0; }
inline void clearLane(int64_t& m, int) { m = 0; }
inline void clearLane(LaneMasks& m, int k) { m[k] = 0; }

/// Whether x is finite (std::isfinite), as a mask.
template <class T>
inline MaskOf<T> finiteOf(const T& x) {
  return maskOf(absOf(x) <= kMaxDouble);
}
/// std::max(a, b) and std::min(a, b): the same operand on ties and NaN.
template <class T>
inline T maxOf(const T& a, const T& b) {
  return select(maskOf(a < b), b, a);
}
template <class T>
inline T minOf(const T& a, const T& b) {
  return select(maskOf(b < a), b, a);
}
/// |(x, y)| as glm::length computes it.
template <class T>
inline T length(const T& x, const T& y) {
  return sqrtOf(x * x + y * y);
}

// ---- The inverse.

/// Past the table, where nothing bounds r: the first of max(1, t, 2·lo)·2^k with ρ >= t; false
/// where ρ stays below t up to 1e300.
bool radialBracketEnd(const DistortionTerms& terms, double t, double lo, double& hi) {
  double rho = 0, drho = 0;
  for (hi = std::max({1.0, t, 2 * lo});; hi *= 2) {
    radialProfileOf(terms, hi, rho, drho);
    if (!(rho < t)) return true;
    if (hi > 1e300) return false;
  }
}

/// Lanes to an array and back (memcpy: one vector store or load).
template <class T>
inline void toArray(const T& v, double* a) {
  std::memcpy(a, &v, sizeof(T));
}
template <class T>
inline T fromArray(const double* a) {
  T v;
  std::memcpy(&v, a, sizeof(T));
  return v;
}

/// The table's cells of `at` (a cell index, fractional): its ends' radii and slopes and the
/// fraction s inside it.
template <class T>
inline void tableCells(const double* radius, const double* slope, const T& at, T& lo, T& hi,
                       T& slopeLo, T& slopeHi, T& s) {
  constexpr int kW = kWidthOf<T>;
  alignas(64) double a[kW], l[kW], h[kW], sl[kW], sh[kW], f[kW];
  toArray(at, a);
  for (int k = 0; k < kW; ++k) {
    const int i = static_cast<int>(a[k]);
    f[k] = a[k] - i;
    l[k] = radius[i], h[k] = radius[i + 1], sl[k] = slope[i], sh[k] = slope[i + 1];
  }
  lo = fromArray<T>(l), hi = fromArray<T>(h), slopeLo = fromArray<T>(sl);
  slopeHi = fromArray<T>(sh), s = fromArray<T>(f);
}

/// The r in the valid region with ρ(r) = t, for the lanes of `solve`; returns the lanes that
/// have one. Not `exact`: the table's first guess where it has one.
template <class T>
MaskOf<T> invertRadial(const LensInverse& c, const T& t, bool exact, T& r, MaskOf<T> solve) {
  using M = MaskOf<T>;
  static const double kNoTable[2] = {0, 0};
  const int cells = c.cells();
  const double* radius = cells > 0 ? c.inverseRadius.data() : kNoTable;
  const double* slope = cells > 0 ? c.inverseSlope.data() : kNoTable;
  const M wanted = solve & maskOf(t >= 0.0);
  const M zero = wanted & maskOf(t == 0.0);
  const M live = wanted & ~zero & (c.bounded ? maskOf(t < c.maxDistorted) : allOf<M>(true));
  // The bracket [lo, hi] (ρ(lo) <= t <= ρ(hi)) and the first guess: the table's cell of t with
  // cubic Hermite interpolation, past the table from its end to the fold, or by doubling where
  // nothing bounds r.
  const T cell = cells > 0 ? t / c.step : splat<T>(kInf);
  const M inTable = maskOf(cell < double(cells));
  T tableLo, tableHi, slopeLo, slopeHi, s;
  tableCells(radius, slope, select(inTable, cell, splat<T>(0.0)), tableLo, tableHi, slopeLo,
             slopeHi, s);
  const double w = c.step;
  const T guess = (1 + 2 * s) * (1 - s) * (1 - s) * tableLo + s * (1 - s) * (1 - s) * w * slopeLo +
                  s * s * (3 - 2 * s) * tableHi + s * s * (s - 1) * w * slopeHi;
  const M firstGuess = live & inTable & allOf<M>(!exact);
  T lo = select(inTable, tableLo, splat<T>(radius[cells]));
  T hi = select(inTable, tableHi, splat<T>(c.maxUndistorted));
  r = select(zero, splat<T>(0.0),
             select(firstGuess, minOf(maxOf(guess, tableLo), tableHi), select(inTable, guess, t)));
  M running = live & ~firstGuess;
  M solved = zero | firstGuess;
  const M doubling = live & ~inTable & allOf<M>(!c.bounded);
  if (any(doubling))  // rare: an unbounded lens beyond its table
    for (int k = 0; k < kWidthOf<T>; ++k) {
      double end = 0;
      if (!isSet(doubling, k)) continue;
      if (radialBracketEnd(c.terms, get(t, k), get(lo, k), end))
        set(hi, k, end);
      else
        clearLane(running, k);
    }
  r = select(running & ~(maskOf(r > lo) & maskOf(r < hi)), 0.5 * (lo + hi), r);
  // Newton on ρ(r) = t, kept inside the bracket by bisection: every running lane one step per
  // round.
  for (int round = 0; round < kMaxRadialIterations && any(running); ++round) {
    T rho, drho;
    radialProfileOf(c.terms, r, rho, drho);
    const T f = rho - t;
    const M below = maskOf(f < 0.0), zeroResidual = maskOf(f == 0.0);
    const T newLo = select(below, r, lo), newHi = select(below, hi, r);
    const T newton = r - f / drho;
    const T next =
        select(maskOf(newton > newLo) & maskOf(newton < newHi), newton, 0.5 * (newLo + newHi));
    const M converged = maskOf(absOf(next - r) <= 1e-15 * r);
    const M accepted =
        maskOf(absOf(f) <= kAcceptedResidual * maxOf(splat<T>(1.0), t)) & maskOf(drho > 0.0);
    solved = select(running & (zeroResidual | converged),
                    select(zeroResidual, maskOf(drho > 0.0), accepted), solved);
    r = select(running & ~zeroResidual, next, r);
    lo = select(running, newLo, lo);
    hi = select(running, newHi, hi);
    running = running & ~zeroResidual & ~converged;
  }
  return solved;
}

/// Newton's method on the 2D map from (x, y) towards (tx, ty), for the lanes of `solve`;
/// returns the lanes solved: converged, inside the valid region, with a positive Jacobian
/// determinant.
template <class T>
MaskOf<T> newton2d(const LensInverse& c, const T& tx, const T& ty, T& x, T& y, MaskOf<T> solve) {
  using M = MaskOf<T>;
  const DistortionTerms& terms = c.terms;
  const T scale = maxOf(splat<T>(1.0), length(tx, ty));
  T j[4], du, dv;
  distortPoint(terms, x, y, du, dv, true, j);
  T rx = du - tx, ry = dv - ty;
  T error = length(rx, ry);
  T sx = splat<T>(0.0), sy = splat<T>(0.0);
  M running = solve, stalled = M{}, solved = M{};
  for (int i = 0; any(running); ++i) {
    const T det = j[0] * j[3] - j[2] * j[1];
    const M broken = ~(finiteOf(error) & finiteOf(det) & maskOf(det != 0.0));
    const M converged = maskOf(error <= kConvergedResidual * scale) |
                        (stalled & maskOf(error <= kAcceptedResidual * scale));
    // A solution on the folded side of the map (det < 0) or past the radial fold is not the
    // inverse: no ray.
    const M inverse = maskOf(det > 0.0) & maskOf(length(x, y) < c.maxUndistorted);
    const M run = running & ~broken;
    solved = select(run & converged, inverse, solved);
    const M steps = run & ~converged & ~stalled & allOf<M>(i != kMaxNewtonIterations);
    // step = J⁻¹ · residual, written out for the 2 × 2 case.
    sx = select(steps, (j[3] * rx - j[2] * ry) / det, sx);
    sy = select(steps, (-j[1] * rx + j[0] * ry) / det, sy);
    stalled = stalled | steps;
    running = steps;
    // Each step is halved until the new point stays inside the radial fold and does not raise
    // the residual (near a fold the full step can overshoot onto the other side). No decrease
    // in kMaxHalvings: the residual is at its floor, and the lane stays stalled.
    M searching = steps;
    for (int h = 0; h < kMaxHalvings && any(searching); ++h) {
      const T nx = x - sx, ny = y - sy;
      const T reach = length(nx, ny);
      T nj[4], ndu, ndv;
      distortPoint(terms, nx, ny, ndu, ndv, true, nj);
      const T nrx = ndu - tx, nry = ndv - ty;
      const T nextError = length(nrx, nry);
      const M accept = searching & maskOf(reach < c.maxUndistorted) & maskOf(nextError <= error);
      const M flat = maskOf(length(sx, sy) <= kStalledStep * maxOf(splat<T>(1.0), reach));
      stalled = select(accept, flat, stalled);
      x = select(accept, nx, x), y = select(accept, ny, y);
      for (int e = 0; e < 4; ++e) j[e] = select(accept, nj[e], j[e]);
      rx = select(accept, nrx, rx), ry = select(accept, nry, ry);
      error = select(accept, nextError, error);
      searching = searching & ~accept;
      sx = select(searching, sx * 0.5, sx), sy = select(searching, sy * 0.5, sy);
    }
  }
  return solved;
}

/// The undistorted (u, v) of the normalised distorted (du, dv), for the lanes of `solve`;
/// returns the lanes with a preimage in the valid region.
template <class T>
MaskOf<T> undistort(const LensInverse& c, const T& du, const T& dv, T& u, T& v, MaskOf<T> solve) {
  using M = MaskOf<T>;
  solve = solve & finiteOf(du) & finiteOf(dv);
  const T t = select(solve, length(du, dv), splat<T>(0.0));
  u = du, v = dv;
  if (c.terms.identity) return solve & maskOf(t < c.maxUndistorted);  // a fisheye's θ >= π
  // Every model maps 0 to 0 with the identity Jacobian: t = 0 needs no inverse.
  const M atZero = solve & maskOf(t == 0.0);
  T r = splat<T>(0.0);
  const M radial = invertRadial(c, t, c.terms.radialOnly, r, solve & ~atZero);
  // Radial models: (u', v') = (ρ(r)/r)·(u, v) points along (u, v), so the radial inverse is the
  // whole inverse, with the same residual, and ρ' > 0, ρ > 0 inside the fold make the
  // Jacobian's determinant (ρ/r)·ρ' positive. Otherwise Newton on the 2D map starts from the
  // radial inverse along the point's own direction; when the radial part alone has no inverse
  // there, just inside the fold, unless the point lies beyond the terms' reach.
  const T along = select(radial, r / t, 0.99 * c.maxUndistorted / t);
  u = select(atZero, splat<T>(0.0), du * along), v = select(atZero, splat<T>(0.0), dv * along);
  if (c.terms.radialOnly) return atZero | radial;
  const M reachable = radial | (c.bounded ? maskOf(t < c.nonRadialLimit) : M{});
  return atZero | newton2d(c, du, dv, u, v, solve & ~atZero & reachable);
}

/// The unit camera-space directions of pixels (px, py) (COLMAP pixel coordinates), for the
/// lanes of `solve`; returns the lanes with a ray.
template <class T>
MaskOf<T> unproject(const LensInverse& c, const T& px, const T& py, T& dx, T& dy, T& dz,
                    MaskOf<T> solve) {
  const T du = (px - c.cx) / c.fx, dv = (py - c.cy) / c.fy;
  T u, v;
  solve = undistort(c, du, dv, u, v, solve);
  if (!c.fisheye) {
    // glm::normalize(dvec3(u, v, 1)): times 1 / √((u² + v²) + 1).
    const T inv = 1.0 / sqrtOf((u * u + v * v) + 1.0 * 1.0);
    dx = u * inv, dy = v * inv, dz = 1.0 * inv;
    return solve;
  }
  // (u, v) = θ·(x, y)/|(x, y)|: the ray at θ off-axis along the azimuth of (u, v).
  constexpr int kW = kWidthOf<T>;
  alignas(64) double us[kW], vs[kW], xs[kW], ys[kW], zs[kW];
  toArray(u, us), toArray(v, vs);
  for (int k = 0; k < kW; ++k) {
    const double theta = std::sqrt(us[k] * us[k] + vs[k] * vs[k]);
    if (!isSet(solve, k) || theta == 0) {
      xs[k] = 0, ys[k] = 0, zs[k] = 1;
      continue;
    }
    const double s = std::sin(theta) / theta;
    xs[k] = us[k] * s, ys[k] = vs[k] * s, zs[k] = std::cos(theta);
  }
  dx = fromArray<T>(xs), dy = fromArray<T>(ys), dz = fromArray<T>(zs);
  return solve;
}

// ---- A model's own formula (LensFormula): one pixel at a time, in double.

/// The r in the valid region with ρ(r) = t (t >= 0): the formula's closed form, or Newton's
/// method kept inside the bracket [0, the fold] by bisection.
bool invertFormula(const LensInverse& c, double t, double& r) {
  if (!(t >= 0)) return false;
  if (t == 0) {
    r = 0;
    return true;
  }
  if (c.bounded && !(t < c.maxDistorted)) return false;
  const double* k = c.coefficients.data();
  if (c.formula->inverse) {
    r = c.formula->inverse(k, t);
    return r >= 0 && r < c.maxUndistorted;
  }
  double lo = 0, hi = c.maxUndistorted, rho = 0, drho = 0;
  if (!c.bounded) {
    for (hi = std::max(1.0, t);; hi *= 2) {
      c.formula->profile(k, hi, rho, drho);
      if (!(rho < t)) break;
      if (hi > 1e300) return false;
    }
  }
  r = std::min(t, 0.5 * (lo + hi));
  for (int i = 0; i < kMaxRadialIterations; ++i) {
    c.formula->profile(k, r, rho, drho);
    const double f = rho - t;
    if (f == 0) return drho > 0;
    (f < 0 ? lo : hi) = r;
    const double newton = r - f / drho;
    const double next = newton > lo && newton < hi ? newton : 0.5 * (lo + hi);
    if (std::abs(next - r) <= 1e-15 * r)
      return std::abs(f) <= kAcceptedResidual * std::max(1.0, t) && drho > 0;
    r = next;
  }
  return false;
}

/// Newton's method on a formula's 2D map from (x, y) towards (tx, ty), as newton2d: solved
/// when converged inside the radial fold with a positive Jacobian determinant.
bool newtonFormula(const LensInverse& c, double tx, double ty, double& x, double& y) {
  const double scale = std::max(1.0, std::sqrt(tx * tx + ty * ty));
  double du = 0, dv = 0, j[4];
  distortByFormula(c, x, y, du, dv, j);
  double rx = du - tx, ry = dv - ty, error = std::sqrt(rx * rx + ry * ry);
  bool stalled = false;
  for (int i = 0;; ++i) {
    const double det = j[0] * j[3] - j[2] * j[1];
    if (!(std::isfinite(error) && std::isfinite(det) && det != 0)) return false;
    if (error <= kConvergedResidual * scale || (stalled && error <= kAcceptedResidual * scale))
      return det > 0 && std::sqrt(x * x + y * y) < c.maxUndistorted;
    if (stalled || i == kMaxNewtonIterations) return false;
    double sx = (j[3] * rx - j[2] * ry) / det, sy = (-j[1] * rx + j[0] * ry) / det;
    stalled = true;  // unless a step below lowers the residual
    for (int h = 0; h < kMaxHalvings; ++h) {
      const double nx = x - sx, ny = y - sy, reach = std::sqrt(nx * nx + ny * ny);
      double ndu = 0, ndv = 0, nj[4];
      distortByFormula(c, nx, ny, ndu, ndv, nj);
      const double nrx = ndu - tx, nry = ndv - ty, nextError = std::sqrt(nrx * nrx + nry * nry);
      if (reach < c.maxUndistorted && nextError <= error) {
        stalled = std::sqrt(sx * sx + sy * sy) <= kStalledStep * std::max(1.0, reach);
        x = nx, y = ny, rx = nrx, ry = nry, error = nextError;
        for (int e = 0; e < 4; ++e) j[e] = nj[e];
        break;
      }
      sx *= 0.5, sy *= 0.5;
    }
  }
}

bool undistortFormula(const LensInverse& c, double du, double dv, double& u, double& v) {
  if (!std::isfinite(du) || !std::isfinite(dv)) return false;
  const double t = std::sqrt(du * du + dv * dv);
  double r = 0;
  const bool radial = invertFormula(c, t, r);
  if (!c.formula->nonRadial) {
    if (!radial) return false;
    const double along = t == 0 ? 0.0 : r / t;
    u = du * along, v = dv * along;
    return true;
  }
  // As undistort(): from the radial inverse along the point's direction, or from just inside
  // the fold when the radial part alone has none there, unless the point lies beyond the
  // non-radial terms' reach.
  if (t == 0) {
    u = v = 0;
  } else {
    if (!radial && !(t < c.nonRadialLimit)) return false;
    const double along = radial ? r / t : 0.99 * c.maxUndistorted / t;
    u = du * along, v = dv * along;
  }
  return newtonFormula(c, du, dv, u, v);
}

bool unprojectFormula(const LensInverse& c, double px, double py, double dir[3]) {
  if (c.formula->rayOf) return c.formula->rayOf(c.coefficients.data(), px, py, dir);
  double u = 0, v = 0;
  if (!undistortFormula(c, (px - c.cx) / c.fx, (py - c.cy) / c.fy, u, v)) return false;
  if (!c.fisheye) {
    const double inv = 1.0 / std::sqrt((u * u + v * v) + 1.0);
    dir[0] = u * inv, dir[1] = v * inv, dir[2] = inv;
    return true;
  }
  const double theta = std::sqrt(u * u + v * v);
  const double s = theta == 0 ? 0.0 : std::sin(theta) / theta;
  dir[0] = u * s, dir[1] = v * s, dir[2] = std::cos(theta);
  return true;
}

/// unprojectEight's kernel.
void unprojectEightLanes(const LensInverse& lens, const double* px, const double* py, double* dirX,
                         double* dirY, double* dirZ, bool* solve) {
  Lanes x, y, dx = {}, dy = {}, dz = {};
  LaneMasks wanted;
  for (int k = 0; k < kLensLanes; ++k) x[k] = px[k], y[k] = py[k], wanted[k] = maskOf(solve[k]);
  const LaneMasks solved = unproject(lens, x, y, dx, dy, dz, wanted);
  for (int k = 0; k < kLensLanes; ++k) {
    dirX[k] = dx[k], dirY[k] = dy[k], dirZ[k] = dz[k];
    solve[k] = solved[k] != 0;
  }
}

}  // namespace

void distortByFormula(const LensInverse& c, double u, double v, double& du, double& dv, double* j) {
  // The radial part (x, y) = (ρ(r)/r)·(u, v), whose Jacobian is (ρ/r)·I plus
  // (ρ' − ρ/r)·n nᵀ along the unit radius n.
  const double* k = c.coefficients.data();
  const double r = std::sqrt(u * u + v * v);
  double rho = 0, drho = 0;
  c.formula->profile(k, r, rho, drho);
  const double gain = r == 0 ? drho : rho / r;
  const double x = u * gain, y = v * gain;
  double jr[4] = {drho, 0, 0, drho};
  if (r > 0) {
    const double nx = u / r, ny = v / r, extra = drho - gain;
    jr[0] = gain + extra * nx * nx, jr[1] = extra * nx * ny;
    jr[2] = extra * nx * ny, jr[3] = gain + extra * ny * ny;
  }
  if (!c.formula->nonRadial) {
    du = x, dv = y;
    if (j)
      for (int e = 0; e < 4; ++e) j[e] = jr[e];
    return;
  }
  double dx = 0, dy = 0, jn[4];
  c.formula->nonRadial(k, x, y, dx, dy, j ? jn : nullptr);
  du = x + dx, dv = y + dy;
  if (!j) return;
  // (I + Jn)·Jr, column by column.
  for (int col = 0; col < 2; ++col) {
    const double a = jr[2 * col], b = jr[2 * col + 1];
    j[2 * col] = (1 + jn[0]) * a + jn[2] * b;
    j[2 * col + 1] = jn[1] * a + (1 + jn[3]) * b;
  }
}

void unprojectEight(const LensInverse& lens, const double* px, const double* py, double* dirX,
                    double* dirY, double* dirZ, bool* solve) {
  if (lens.formula) {  // a model's own formula: one pixel at a time
    for (int k = 0; k < kLensLanes; ++k) {
      double dir[3] = {0, 0, 1};
      solve[k] = solve[k] && unprojectFormula(lens, px[k], py[k], dir);
      dirX[k] = dir[0], dirY[k] = dir[1], dirZ[k] = dir[2];
    }
    return;
  }
  runKernel<&unprojectEightLanes>(lens, px, py, dirX, dirY, dirZ, solve);
}

bool unprojectOne(const LensInverse& lens, double px, double py, double dir[3]) {
  if (lens.formula) return unprojectFormula(lens, px, py, dir);
  return unproject(lens, px, py, dir[0], dir[1], dir[2], maskOf(true)) != 0;
}

bool undistortOne(const LensInverse& lens, double du, double dv, double& u, double& v) {
  if (lens.formula) return undistortFormula(lens, du, dv, u, v);
  return undistort(lens, du, dv, u, v, maskOf(true)) != 0;
}

bool invertRadialOne(const LensInverse& lens, double t, bool exact, double& r) {
  if (lens.formula) return invertFormula(lens, t, r);
  return invertRadial(lens, t, exact, r, maskOf(true)) != 0;
}

}  // namespace aperture
