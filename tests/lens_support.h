#pragma once
// Helpers of the lens model tests (tests/cameras/lenses/test_lens_model*.cpp): the parameter
// sets (COLMAP's, harder ones of our own, COLMAP 4's models) and the sampling of directions in a
// lens's valid region.
#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <random>
#include <utility>
#include <vector>

#include "cameras/lenses/lens_model.h"
#include "core/util/units.h"

namespace aperture::test {

struct LensCase {
  const char* label;
  LensModelId model;
  std::vector<double> params;
};

// COLMAP's parameter sets from models_test.cc (taken as facts).
inline std::vector<LensCase> colmapCases() {
  return {
      {"SIMPLE_PINHOLE", LensModelId::SimplePinhole, {655.123, 386.123, 511.123}},
      {"PINHOLE", LensModelId::Pinhole, {651.123, 655.123, 386.123, 511.123}},
      {"SIMPLE_RADIAL k=0", LensModelId::SimpleRadial, {651.123, 386.123, 511.123, 0}},
      {"SIMPLE_RADIAL k=0.1", LensModelId::SimpleRadial, {651.123, 386.123, 511.123, 0.1}},
      {"RADIAL 0 0", LensModelId::Radial, {651.123, 386.123, 511.123, 0, 0}},
      {"RADIAL 0.1 0", LensModelId::Radial, {651.123, 386.123, 511.123, 0.1, 0}},
      {"RADIAL 0 0.05", LensModelId::Radial, {651.123, 386.123, 511.12, 0, 0.05}},
      {"RADIAL 0.05 0.03", LensModelId::Radial, {651.123, 386.123, 511.123, 0.05, 0.03}},
      {"OPENCV",
       LensModelId::OpenCV,
       {651.123, 655.123, 386.123, 511.123, -0.471, 0.223, -0.001, 0.001}},
      {"OPENCV_FISHEYE",
       LensModelId::OpenCVFisheye,
       {651.123, 655.123, 386.123, 511.123, -0.471, 0.223, -0.001, 0.001}},
      {"FULL_OPENCV",
       LensModelId::FullOpenCV,
       {651.123, 655.123, 386.123, 511.123, -0.471, 0.223, -0.001, 0.001, 0.001, 0.02, -0.02,
        0.001}},
      {"SIMPLE_RADIAL_FISHEYE k=0",
       LensModelId::SimpleRadialFisheye,
       {651.123, 386.123, 511.123, 0}},
      {"SIMPLE_RADIAL_FISHEYE k=0.1",
       LensModelId::SimpleRadialFisheye,
       {651.123, 386.123, 511.123, 0.1}},
      {"RADIAL_FISHEYE 0 0", LensModelId::RadialFisheye, {651.123, 386.123, 511.123, 0, 0}},
      {"RADIAL_FISHEYE 0 0.1", LensModelId::RadialFisheye, {651.123, 386.123, 511.123, 0, 0.1}},
      {"RADIAL_FISHEYE 0 0.05", LensModelId::RadialFisheye, {651.123, 386.123, 511.123, 0, 0.05}},
      {"RADIAL_FISHEYE 0 0.03", LensModelId::RadialFisheye, {651.123, 386.123, 511.123, 0, 0.03}},
      {"THIN_PRISM_FISHEYE",
       LensModelId::ThinPrismFisheye,
       {651.123, 655.123, 386.123, 511.123, -0.471, 0.223, -0.001, 0.001, 0.001, 0.02, -0.02,
        0.001}},
  };
}

// Our own harder sets: strong radial distortion both ways, folds (polynomial, rational,
// fisheye), strong tangential and thin-prism terms.
inline std::vector<LensCase> extremeCases() {
  return {
      {"SIMPLE_RADIAL k=+0.5", LensModelId::SimpleRadial, {500, 320, 240, 0.5}},
      {"SIMPLE_RADIAL k=-0.5", LensModelId::SimpleRadial, {500, 320, 240, -0.5}},
      {"RADIAL fold", LensModelId::Radial, {500, 320, 240, 0.1, -0.05}},
      {"OPENCV k1=+0.5", LensModelId::OpenCV, {500, 510, 320, 240, 0.5, 0, 0.01, -0.01}},
      {"OPENCV k1=-0.5", LensModelId::OpenCV, {500, 510, 320, 240, -0.5, 0, 0.01, -0.01}},
      {"OPENCV tangential", LensModelId::OpenCV, {500, 510, 320, 240, -0.2, 0.05, 0.03, -0.02}},
      {"FULL_OPENCV rational fold",
       LensModelId::FullOpenCV,
       {500, 510, 320, 240, 0, 0, 0, 0, 0, 1, 0, 0}},
      {"FULL_OPENCV pole",
       LensModelId::FullOpenCV,
       {500, 510, 320, 240, 0.1, 0, 0.002, 0.001, 0, -0.2, 0, 0}},
      {"OPENCV_FISHEYE equidistant", LensModelId::OpenCVFisheye, {300, 300, 320, 240, 0, 0, 0, 0}},
      {"SIMPLE_RADIAL_FISHEYE fold", LensModelId::SimpleRadialFisheye, {300, 320, 240, -0.1}},
      {"RADIAL_FISHEYE -0.05 0.002", LensModelId::RadialFisheye, {300, 320, 240, -0.05, 0.002}},
      {"THIN_PRISM_FISHEYE prism",
       LensModelId::ThinPrismFisheye,
       {300, 310, 320, 240, 0.02, -0.01, 0.004, -0.003, 0.001, 0, 0.01, -0.008}},
  };
}

// The models COLMAP 4 added (issue 40), each reaching past what it sees inside a 1600 x 1200
// image (behind the camera, a fold, the limit of its formula).
inline std::vector<LensCase> colmap4Cases() {
  return {
      {"FOV ω=0.9", LensModelId::FOV, {500, 510, 320, 240, 0.9}},
      {"FOV ω=0", LensModelId::FOV, {500, 510, 320, 240, 0}},
      {"SIMPLE_DIVISION k=-0.3 (behind the camera)",
       LensModelId::SimpleDivision,
       {300, 320, 240, -0.3}},
      {"DIVISION k=+0.2 (fold)", LensModelId::Division, {500, 510, 320, 240, 0.2}},
      {"SIMPLE_FISHEYE", LensModelId::SimpleFisheye, {300, 320, 240}},
      {"FISHEYE", LensModelId::Fisheye, {300, 310, 320, 240}},
      {"EUCM α=0.6 β=1.1 (fold)", LensModelId::EUCM, {400, 410, 320, 240, 0.6, 1.1}},
      {"EUCM α=0.3 β=0.8", LensModelId::EUCM, {400, 410, 320, 240, 0.3, 0.8}},
      {"EQUIRECTANGULAR", LensModelId::Equirectangular, {1600, 800}},
      {"RAD_TAN_THIN_PRISM_FISHEYE",
       LensModelId::RadTanThinPrismFisheye,
       {300, 310, 320, 240, 0.02, -0.01, 0.002, -1e-4, 0, 0, 0.004, -0.003, 0.01, -0.002, -0.008,
        0.001}},
  };
}

inline std::vector<LensCase> allCases() {
  std::vector<LensCase> all = colmapCases();
  for (LensCase& c : extremeCases()) all.push_back(std::move(c));
  for (LensCase& c : colmap4Cases()) all.push_back(std::move(c));
  return all;
}

inline Lens lensOf(const LensCase& c) { return Lens(c.model, c.params); }

/// How far out the random points go: 98% of the valid region (r or θ), and r <= 3 (71.6°
/// off-axis) for the pinhole models without a fold.
inline double sampleRadius(const Lens& lens) {
  const double cap = lens.overTheta() ? kPi : 3.0;
  return 0.98 * std::min(lens.validRegion().maxUndistorted, cap);
}

inline glm::dvec2 randomInDisc(std::mt19937_64& rng, double radius) {
  std::uniform_real_distribution<double> unit(0, 1);
  const double r = radius * std::sqrt(unit(rng)), phi = 2 * kPi * unit(rng);
  return {r * std::cos(phi), r * std::sin(phi)};
}

/// The camera-space direction of undistorted normalised coordinates.
inline glm::dvec3 directionOf(const Lens& lens, const glm::dvec2& u) {
  if (!lens.overTheta()) return glm::normalize(glm::dvec3(u, 1.0));
  const double theta = glm::length(u);
  if (theta == 0) return {0, 0, 1};
  return {std::sin(theta) * u.x / theta, std::sin(theta) * u.y / theta, std::cos(theta)};
}

/// Whether the distortion has a term that is not radial (it can fold the map in 2D).
inline bool hasNonRadialTerms(const LensCase& c) {
  const std::vector<double>& p = c.params;
  switch (c.model) {
    case LensModelId::OpenCV:
      return p[6] != 0 || p[7] != 0;
    case LensModelId::FullOpenCV:
      return p[6] != 0 || p[7] != 0;
    case LensModelId::ThinPrismFisheye:
      return p[6] != 0 || p[7] != 0 || p[10] != 0 || p[11] != 0;
    case LensModelId::RadTanThinPrismFisheye:
      return true;
    default:
      return false;
  }
}

}  // namespace aperture::test
