// COLMAP's camera models: the table, parameter access, and (to be filled in) the forward
// model, its Jacobian, the inverse by Newton's method and the valid region.
#include "cameras/lens_model.h"

#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/spelling.h"

namespace aperture {

const std::vector<LensModelInfo>& lensModels() {
  static const std::vector<LensModelInfo> models = {
      {LensModelId::SimplePinhole, "SIMPLE_PINHOLE", 0, {"f", "cx", "cy"}, false},
      {LensModelId::Pinhole, "PINHOLE", 1, {"fx", "fy", "cx", "cy"}, false},
      {LensModelId::SimpleRadial, "SIMPLE_RADIAL", 2, {"f", "cx", "cy", "k"}, false},
      {LensModelId::Radial, "RADIAL", 3, {"f", "cx", "cy", "k1", "k2"}, false},
      {LensModelId::OpenCV, "OPENCV", 4, {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"}, false},
      {LensModelId::OpenCVFisheye,
       "OPENCV_FISHEYE",
       5,
       {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"},
       true},
      {LensModelId::FullOpenCV,
       "FULL_OPENCV",
       6,
       {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"},
       false},
      {LensModelId::SimpleRadialFisheye, "SIMPLE_RADIAL_FISHEYE", 8, {"f", "cx", "cy", "k"}, true},
      {LensModelId::RadialFisheye, "RADIAL_FISHEYE", 9, {"f", "cx", "cy", "k1", "k2"}, true},
      {LensModelId::ThinPrismFisheye,
       "THIN_PRISM_FISHEYE",
       10,
       {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "sx1", "sy1"},
       true},
  };
  return models;
}

const LensModelInfo& lensModelInfo(LensModelId id) {
  for (const LensModelInfo& m : lensModels())
    if (m.id == id) return m;
  throw Error("internal: unknown lens model id");
}

const LensModelInfo& findLensModel(const std::string& name) {
  std::string upper = name;
  for (char& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
  std::vector<std::string> names;
  for (const LensModelInfo& m : lensModels()) {
    if (upper == m.name) return m;
    names.emplace_back(m.name);
  }
  throw Error(cat("unsupported camera model '", name, "' (supported: ", join(names, ", "), ")",
                  didYouMean(upper, names)));
}

const LensModelInfo* findLensModelByColmapId(int colmapId) {
  for (const LensModelInfo& m : lensModels())
    if (m.colmapId == colmapId) return &m;
  return nullptr;
}

Lens::Lens(LensModelId model, std::vector<double> params)
    : model_(model), params_(std::move(params)) {
  const LensModelInfo& m = info();
  if (params_.size() != m.paramNames.size())
    throw Error(cat("camera model ", m.name, " takes ", m.paramNames.size(), " parameters (",
                    join(m.paramNames, " "), "), got ", params_.size()));
  for (size_t i = 0; i < params_.size(); ++i)
    if (!std::isfinite(params_[i]))
      throw Error(cat("camera model ", m.name, ": parameter ", m.paramNames[i], " is ", params_[i],
                      " (must be finite)"));
  if (fx() <= 0 || fy() <= 0)
    throw Error(
        cat("camera model ", m.name, ": focal length must be > 0 (got ", fx(), ", ", fy(), ")"));
}

double Lens::fx() const { return params_[0]; }
double Lens::fy() const { return info().singleFocal() ? params_[0] : params_[1]; }
double Lens::cx() const { return params_[info().singleFocal() ? 1 : 2]; }
double Lens::cy() const { return params_[info().singleFocal() ? 2 : 3]; }

std::vector<double> Lens::distortion() const {
  return {params_.begin() + (info().singleFocal() ? 3 : 4), params_.end()};
}

bool Lens::distorted() const {
  if (info().fisheye) return true;
  for (double k : distortion())
    if (k != 0) return true;
  return false;
}

}  // namespace aperture
