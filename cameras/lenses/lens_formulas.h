#pragma once
// The formulas of COLMAP's models that the shared polynomial form (DistortionTerms) does not
// hold, each written from COLMAP's src/colmap/sensor/models.h: its radial profile, the closed
// form of its inverse and the checks of its coefficients. The rows that use them are in
// cameras/lens_model.cpp.
#include "cameras/lenses/lens_inverse.h"

namespace aperture {

/// FOV (Devernay and Faugeras), ω: ρ = atan(2 tan θ tan(ω/2)) / ω, over θ < 90°.
extern const LensFormula kFovFormula;
/// SIMPLE_DIVISION and DIVISION (Fitzgibbon), k: the ray of the distorted radius ρ is
/// (ρ, 1 + kρ²), over θ up to 180° for k < 0.
extern const LensFormula kDivisionFormula;
/// EUCM (Khomutenko et al.), α, β: ρ = sin θ / (α √(β sin²θ + cos²θ) + (1 − α) cos θ).
extern const LensFormula kEucmFormula;
/// RAD_TAN_THIN_PRISM_FISHEYE (Project Aria's Fisheye624), k0..k5, p0, p1, s0..s3: the radial
/// ρ = θ(1 + k0θ² + … + k5θ¹²), then tangential and thin-prism terms on the distorted point.
extern const LensFormula kRadTanThinPrismFormula;
/// EQUIRECTANGULAR, w, h: longitude 2π(x/w − ½) across, latitude π(½ − y/h) down; every
/// direction of the sphere has its pixel.
extern const LensFormula kEquirectangularFormula;

}  // namespace aperture
