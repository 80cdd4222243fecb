#pragma once
// The arithmetic of the calibrated lens models, and the exact inverse's kernel. A Lens
// (cameras/lenses/lens_model.h) owns a model and its parameters; what its forward map and its
// inverse compute is written here once, as templates over the number type: a double for one point,
// or eight of them side by side (GCC's vector extension, one AVX-512 register, two AVX2 ones)
// for the inverse of eight pixels. Either way each lane computes exactly the same operations
// in the same order: IEEE +, −, ×, ÷ and √ round the same in every vector width, and the build
// contracts no FMA.
#include <cstdint>
#include <vector>

namespace aperture {

/// Every model's distortion in one shared form, filled from the parameters once:
///   (u', v') = g(s)·(u, v) + tangential(u, v) + (sx1, sy1)·s,   s = u² + v²,
///   g(s) = N(s) / D(s),  N = 1 + n1 s + … + n4 s⁴,  D = 1 + d1 s + d2 s² + d3 s³,
///   tangential = (2 p1 u v + p2 (s + 2u²), 2 p2 u v + p1 (s + 2v²)).
struct DistortionTerms {
  double num[5] = {1, 0, 0, 0, 0};  ///< N's coefficients by power of s
  double den[4] = {1, 0, 0, 0};     ///< D's (FULL_OPENCV's k4, k5, k6)
  double p1 = 0, p2 = 0;            ///< tangential (OpenCV's p1, p2)
  double sx1 = 0, sy1 = 0;          ///< thin prism
  bool identity = true;             ///< no distortion at all: (u', v') = (u, v)
  bool rational = false;            ///< D is not 1
  bool radialOnly = true;           ///< no tangential or thin-prism term
};

/// Σ c[i] sⁱ (i < N, N >= 2) and its derivative by s, by Horner's rule (from p = c[N − 1],
/// dp = 0; the first step written out, so every step's operands have the type of s).
template <int N, class T>
inline T polynomialAt(const double* c, T s, T& derivative) {
  T dp = 0.0 * s + c[N - 1];
  T p = c[N - 1] * s + c[N - 2];
  for (int i = N - 3; i >= 0; --i) {
    dp = dp * s + p;
    p = p * s + c[i];
  }
  derivative = dp;
  return p;
}

/// g(s) and dg/ds.
template <class T>
inline void distortionGain(const DistortionTerms& t, T s, T& g, T& dg) {
  T dn;
  const T n = polynomialAt<5>(t.num, s, dn);
  if (!t.rational) {
    g = n, dg = dn;
    return;
  }
  T dd;
  const T d = polynomialAt<4>(t.den, s, dd);
  g = n / d;
  dg = (dn * d - n * dd) / (d * d);
}

/// The radial profile ρ(r) = r·g(r²) and its derivative.
template <class T>
inline void radialProfileOf(const DistortionTerms& t, T r, T& rho, T& drho) {
  const T s = r * r;
  T g, dg;
  distortionGain(t, s, g, dg);
  rho = r * g;
  drho = g + 2 * s * dg;
}

/// The forward map (u, v) -> (u', v') of a distorted model (not t.identity) and, when
/// `withJacobian`, d(u', v')/d(u, v) column by column: j[0] = du'/du, j[1] = dv'/du,
/// j[2] = du'/dv, j[3] = dv'/dv.
template <class T>
inline void distortPoint(const DistortionTerms& t, T u, T v, T& du, T& dv, bool withJacobian,
                         T* j) {
  const T uu = u * u, vv = v * v, uv = u * v, s = uu + vv;
  T g, dg;
  distortionGain(t, s, g, dg);
  if (withJacobian) {
    // d(g(s)·u)/du = g + 2u²·g'(s), and so on.
    j[0] = g + 2 * uu * dg + 2 * t.p1 * v + 6 * t.p2 * u + 2 * t.sx1 * u;
    j[1] = 2 * uv * dg + 2 * t.p2 * v + 2 * t.p1 * u + 2 * t.sy1 * u;
    j[2] = 2 * uv * dg + 2 * t.p1 * u + 2 * t.p2 * v + 2 * t.sx1 * v;
    j[3] = g + 2 * vv * dg + 2 * t.p2 * u + 6 * t.p1 * v + 2 * t.sy1 * v;
  }
  du = g * u + 2 * t.p1 * uv + t.p2 * (s + 2 * uu) + t.sx1 * s;
  dv = g * v + 2 * t.p2 * uv + t.p1 * (s + 2 * vv) + t.sy1 * s;
}

/// A model's own distortion, for a model the shared polynomial form (DistortionTerms) does not
/// hold: its radial profile ρ(r), the distorted radius (normalised coordinates) of the
/// undistorted one, r = |(x/z, y/z)| or, `overTheta`, the angle θ off-axis. ρ(0) = 0 and
/// ρ'(0) > 0; ρ is NaN where the model has no image. The valid region ends at the first r
/// where ρ is not finite or ρ' <= 0 (Lens::findValidRegion).
struct LensFormula {
  /// ρ(r) and dρ/dr for the coefficients k (the params after the focal lengths and principal
  /// point, in COLMAP's order).
  void (*profile)(const double* k, double r, double& rho, double& drho) = nullptr;
  /// The exact inverse r(ρ) inside the valid region, when there is a closed form (else the
  /// inverse is Newton's method on `profile`).
  double (*inverse)(const double* k, double rho) = nullptr;
  /// Throws Error (naming `model` and the value) for coefficients the model refuses; null:
  /// any finite values.
  void (*check)(const char* model, const double* k) = nullptr;
  /// The profile is over θ (the ray at θ off-axis, up to π: a model that sees behind the
  /// camera), whatever COLMAP calls the model.
  bool overTheta = false;
  /// Terms that are not radial, added to the radially distorted point (x, y): their value and,
  /// when j is given, their Jacobian by (x, y) column by column (j[0] = d(dx)/dx,
  /// j[1] = d(dy)/dx, j[2] = d(dx)/dy, j[3] = d(dy)/dy). Null: a radial model.
  void (*nonRadial)(const double* k, double x, double y, double& dx, double& dy,
                    double* j) = nullptr;
  /// How far `nonRadial` can move a point of radius <= `radius` (a bound).
  double (*reach)(const double* k, double radius) = nullptr;
  /// A map that is not radial about a principal point (EQUIRECTANGULAR): the unit ray of a
  /// pixel and the pixel of a direction, from all the parameters, and the linear part of the
  /// map as intrinsics. Null: the radial profile above, after the intrinsics.
  bool (*rayOf)(const double* params, double px, double py, double dir[3]) = nullptr;
  bool (*pixelOf)(const double* params, const double dir[3], double& px, double& py) = nullptr;
  void (*intrinsicsOf)(const double* params, double& fx, double& fy, double& cx,
                       double& cy) = nullptr;
};

/// Everything the inverse reads of a lens, made once with it (Lens::inverse_): its terms,
/// intrinsics, valid region and the radial inverse's first-guess table.
struct LensInverse {
  DistortionTerms terms;
  /// The model's own formula (LensModelInfo::formula) and its coefficients; null: `terms`.
  const LensFormula* formula = nullptr;
  std::vector<double> coefficients;
  double fx = 1, fy = 1, cx = 0, cy = 0;
  bool fisheye = false;
  bool bounded = false;       ///< LensValidRegion::bounded()
  double maxUndistorted = 0;  ///< the valid region's radii
  double maxDistorted = 0;
  /// maxDistorted plus how far the tangential and thin-prism terms reach: no distorted point
  /// beyond it has a preimage (Lens::nonRadialReach).
  double nonRadialLimit = 0;
  /// The radial inverse's table: r and dr/dt at t = k·step, k = 0..cells() (empty: none, as
  /// for a lens without distortion or while the table is being made).
  std::vector<double> inverseRadius, inverseSlope;
  double step = 0;
  int cells() const { return inverseRadius.empty() ? 0 : int(inverseRadius.size()) - 1; }
};

/// A formula's whole distortion (u, v) -> (u', v'): the radial profile, then the non-radial
/// terms; `j` (if given) receives the Jacobian column by column, as distortPoint's.
void distortByFormula(const LensInverse& lens, double u, double v, double& du, double& dv,
                      double* j);

/// The radial profile ρ(r) of a lens and dρ/dr, by its formula.
inline void profileOf(const LensInverse& c, double r, double& rho, double& drho) {
  if (c.formula)
    c.formula->profile(c.coefficients.data(), r, rho, drho);
  else
    radialProfileOf(c.terms, r, rho, drho);
}

/// Pixels unprojectEight solves side by side.
inline constexpr int kLensLanes = 8;

/// Lens::unproject of one pixel (COLMAP pixel coordinates): false where it has no ray.
bool unprojectOne(const LensInverse& lens, double px, double py, double dir[3]);
/// Lens::unproject of eight pixels side by side; on entry solve[k] says which to solve, on
/// return whether each has a ray (written to dirX..dirZ[k]).
void unprojectEight(const LensInverse& lens, const double* px, const double* py, double* dirX,
                    double* dirY, double* dirZ, bool* solve);
/// Lens::undistort of one point in normalised coordinates: false where it has no preimage.
bool undistortOne(const LensInverse& lens, double du, double dv, double& u, double& v);
/// The radial profile's inverse of one radius (Lens::invertRadialProfile); `exact` false: the
/// table's first guess where it has one.
bool invertRadialOne(const LensInverse& lens, double t, bool exact, double& r);

}  // namespace aperture
