#pragma once
// Calibrated lens models: COLMAP's camera models (the reference for every formula is COLMAP's
// src/colmap/sensor/models.h), their forward projection and its exact inverse.
//
// Pixel coordinates here are COLMAP's: the centre of pixel (row i, column j) is at
// (j + 0.5, i + 0.5). Camera space is COLMAP's and OpenCV's: x right, y down, z forward.
// Sources with another pixel convention (OpenCV: centre at (j, i)) are converted by
// cameras/lenses/calibration.h, not here.
//
// The inverse maps a pixel to its ray by Newton's method with the analytic Jacobian, in
// double precision (the formulas and the solver: cameras/lenses/lens_inverse.h). Where the forward
// model is not invertible (past the first fold of the radial polynomial, beyond a fisheye's
// fold or beyond 180° off-axis), a pixel has no ray: unproject() returns nothing and the
// renderer records a miss.
#include <deque>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cameras/lenses/lens_inverse.h"

namespace aperture {

/// A lens model's identity: COLMAP's CameraModelId for COLMAP's models. A model registered
/// by registerLensModel takes any other value.
enum class LensModelId : int {
  SimplePinhole = 0,
  Pinhole = 1,
  SimpleRadial = 2,
  Radial = 3,
  OpenCV = 4,
  OpenCVFisheye = 5,
  FullOpenCV = 6,
  FOV = 7,
  SimpleRadialFisheye = 8,
  RadialFisheye = 9,
  ThinPrismFisheye = 10,
  RadTanThinPrismFisheye = 11,
  SimpleDivision = 12,
  Division = 13,
  SimpleFisheye = 14,
  Fisheye = 15,
  EUCM = 16,
  Equirectangular = 17,
};

/// How a camera file format spells a model: its name there and, per coefficient slot of the
/// format, the index of the model's distortion coefficient that fills it (-1: the slot is
/// zero). No name: the format cannot express the model.
struct LensSpelling {
  const char* name = nullptr;
  std::vector<int> slots;
  bool expressible() const { return name != nullptr; }
};

/// One model: everything aperture knows of it, in one row. The readers and writers of camera
/// files, the parameter checks and the formulas all read these rows.
struct LensModelInfo {
  LensModelId id;
  const char* name;                     ///< COLMAP's name: "SIMPLE_RADIAL"
  int colmapId;                         ///< COLMAP's model_id (cameras.bin)
  std::vector<const char*> paramNames;  ///< COLMAP's order: "f", "cx", "cy", "k"
  /// COLMAP's fisheye models: distortion acts on the angle θ off-axis rather than on x/z, y/z
  /// (a formula may also be over θ: LensFormula::overTheta).
  bool fisheye;
  /// The formula, one of two kinds: the coefficients (params after the focal lengths and the
  /// principal point, in COLMAP's order) as terms of the shared polynomial form, or a formula
  /// of the model's own.
  DistortionTerms (*terms)(const double* k) = nullptr;
  const LensFormula* formula = nullptr;
  /// OpenCV's spelling: "standard" (slots k1 k2 p1 p2 k3 k4 k5 k6) or "fisheye" (cv::fisheye,
  /// slots k1 k2 k3 k4).
  LensSpelling opencv;
  /// nerfstudio's camera_model and its slots k1 k2 k3 k4 p1 p2 (camera_utils.py).
  LensSpelling nerfstudio;
  /// Blender's camera type (bpy.types.Camera type / panorama_type) that is this model without
  /// distortion: "PERSP" for the pinholes. No slots: Blender's cameras have no distortion.
  LensSpelling blender;
  bool singleFocal() const { return paramNames[0][1] == '\0'; }  ///< "f" rather than "fx", "fy"
  /// Whether the model maps pixels to rays by a map of its own, without focal lengths and
  /// principal point among its parameters (EQUIRECTANGULAR: LensFormula::rayOf).
  bool ownMap() const { return formula && formula->rayOf; }
  /// The number of parameters before the distortion coefficients (none for an own map: all
  /// its parameters are its coefficients).
  size_t intrinsicCount() const { return ownMap() ? 0 : singleFocal() ? 3 : 4; }
};

/// Every model, COLMAP's in COLMAP's id order, then the registered ones. A deque: a row's
/// address never changes.
const std::deque<LensModelInfo>& lensModels();
const LensModelInfo& lensModelInfo(LensModelId id);
/// The model named `name` (COLMAP's spelling, case-insensitive); throws Error naming it, the
/// supported models and the closest one.
const LensModelInfo& findLensModel(const std::string& name);
/// The model with COLMAP's `colmapId`, or null.
const LensModelInfo* findLensModelByColmapId(int colmapId);
/// Adds a model to the table (a model aperture does not ship, a test's); throws Error when its
/// id, name or COLMAP id is taken, or it has not exactly one formula. Not thread-safe: register
/// before any camera is made. unregisterLensModel removes the last one registered.
const LensModelInfo& registerLensModel(LensModelInfo row);
void unregisterLensModel(LensModelId id);

/// Where the forward model is invertible, computed once per lens. Radii are of the
/// undistorted normalised coordinates |(x/z, y/z)| for the pinhole models and the angle θ
/// off-axis (radians) for the fisheye models; +inf where nothing bounds them (the pinhole
/// models without distortion: any z > 0; a fisheye's angle is bounded by π).
struct LensValidRegion {
  double maxUndistorted = 0;  ///< r or θ at the fold (first zero of the radial derivative)
  double maxDistorted = 0;    ///< the distorted radius there (normalised coordinates)
  bool bounded() const;       ///< whether a fold (or θ = π) limits the model
  /// "r < 1.234 (distorted 0.987, 51.0° off-axis)", "θ < 1.826 rad (distorted 1.217, 104.6°
  /// off-axis)" or "unbounded".
  std::string text(bool fisheye) const;
};

/// A calibrated lens: a model and its parameters in COLMAP's order (focal lengths and
/// principal point in pixels, COLMAP's pixel convention).
class Lens {
 public:
  /// Throws Error for a wrong parameter count (naming the model and the count it takes), a
  /// non-finite parameter or a focal length <= 0.
  Lens(LensModelId model, std::vector<double> params);

  LensModelId model() const { return model_; }
  const LensModelInfo& info() const { return lensModelInfo(model_); }
  const std::vector<double>& params() const { return params_; }
  double fx() const;
  double fy() const;
  double cx() const;
  double cy() const;
  /// The distortion coefficients (params after the focal lengths and principal point).
  std::vector<double> distortion() const;
  /// Whether any distortion coefficient is non-zero (a fisheye model is never "undistorted":
  /// its projection is not a pinhole's even with zero coefficients).
  bool distorted() const;

  /// Forward model: the pixel (COLMAP convention) a camera-space direction (any length > 0)
  /// projects to. Nothing where the direction has no image: z <= 0 for the pinhole models,
  /// θ beyond the valid region for all models.
  std::optional<glm::dvec2> project(const glm::dvec3& dirCamera) const;
  /// Inverse: the unit camera-space direction of a pixel position (COLMAP convention), or
  /// nothing outside the valid region or where Newton's method does not converge.
  std::optional<glm::dvec3> unproject(const glm::dvec2& pixel) const;
  /// Pixels unprojectBatch solves side by side.
  static constexpr int kBatch = kLensLanes;
  /// unproject() of pixels[0, n), n <= kBatch, side by side (cameras/lenses/lens_inverse.h: one
  /// vector lane each). The same directions bit for bit: one implementation serves both.
  /// hasRay[k] is false where unproject() gives nothing; dirs[k] is then unspecified.
  void unprojectBatch(int n, const glm::dvec2* pixels, glm::dvec3* dirs, bool* hasRay) const;

  /// The distortion in normalised coordinates: for the pinhole models (u, v) = (x/z, y/z) to
  /// the distorted (u', v'); for the fisheye models (u, v) = θ·(x, y)/|(x, y)| to the
  /// distorted (u', v'). `jacobian` (if given) receives d(u', v')/d(u, v) (GLM: columns
  /// are the derivatives by u and by v).
  glm::dvec2 distort(const glm::dvec2& undistorted, glm::dmat2* jacobian = nullptr) const;
  /// Its inverse by Newton's method; nothing outside the valid region or without convergence.
  std::optional<glm::dvec2> undistort(const glm::dvec2& distorted) const;

  const LensValidRegion& validRegion() const { return valid_; }
  /// Whether the lens's radii are angles θ off-axis (a fisheye, or a formula over θ).
  bool overTheta() const { return inverse_.fisheye; }

  bool operator==(const Lens& o) const { return model_ == o.model_ && params_ == o.params_; }

 private:
  /// The radial profile ρ(r) = r·g(r²) and its derivative.
  void radialProfile(double r, double& rho, double& drho) const {
    profileOf(inverse_, r, rho, drho);
  }
  /// The r in the valid region with ρ(r) = t (t >= 0), by bracketed Newton; nothing past it.
  /// Not `exact`: the table's first guess where it has one (for the 2D Newton to refine).
  std::optional<double> invertRadialProfile(double t, bool exact = true) const;
  /// Fills the first-guess table of inverse_ (after the rest of it).
  void tabulateInverse();
  LensValidRegion findValidRegion() const;
  /// How far the tangential and thin-prism terms can move a point of the valid region.
  double nonRadialReach() const;
  /// Whether the distortion is radial only (it cannot fold the map in 2D inside the fold).
  bool radialOnly() const {
    return inverse_.formula ? inverse_.formula->nonRadial == nullptr : inverse_.terms.radialOnly;
  }

  LensModelId model_;
  std::vector<double> params_;
  LensValidRegion valid_;
  /// Everything the inverse reads (cameras/lenses/lens_inverse.h), from params_ and valid_: the
  /// intrinsics, the terms, the region's radii and the radial inverse's first-guess table,
  /// made once by the constructor and the one copy of each.
  LensInverse inverse_;
};

}  // namespace aperture
