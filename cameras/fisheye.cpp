// Equidistant fisheye: the angle from the view axis grows linearly with the distance from
// the image centre.
//
// Raster position (x, y), image W x H pixels, circle radius R = min(W, H) / 2 pixels centred
// at (W / 2, H / 2), full field of view F (degrees, at most 360):
//   a = (x − W/2) / R,  b = (H/2 − y) / R,  rho = sqrt(a² + b²)
//   rho > 1: no ray (valid lane 0, a miss)
//   theta = rho · F / 2                          (angle from −W)
//   dir = sin(theta)·(a/rho·U + b/rho·V) − cos(theta)·W   (−W at rho = 0)
// Origin e. Image right is +U, image up is +V.
#include <cmath>

#include "cameras/models.h"
#include "core/error.h"
#include "core/units.h"

namespace aperture {

namespace {

class FisheyeCamera final : public PacketCamera<FisheyeCamera> {
 public:
  FisheyeCamera(const CameraParams& p, const glm::dvec3& renderOrigin)
      : PacketCamera(p, renderOrigin, "fisheye") {
    rejectShift();
    halfFov_ = 0.5 * p.fisheyeFovDeg * kRadPerDeg;
    radius_ = 0.5 * std::min(width_, height_);
    cx_ = 0.5 * width_;
    cy_ = 0.5 * height_;
  }

  bool usesLens() const { return false; }
  bool rayAt(double x, double y, double, double, glm::dvec3& org, glm::dvec3& dir) const {
    const double a = (x - cx_) / radius_, b = (cy_ - y) / radius_;
    const double rho = std::sqrt(a * a + b * b);
    org = renderEyeD_;
    if (rho > 1.0) {
      dir = -frame_.w;
      return false;
    }
    if (rho == 0.0) {
      dir = -frame_.w;
      return true;
    }
    const double theta = rho * halfFov_, s = std::sin(theta) / rho;
    const glm::dvec3 g = (s * a) * frame_.u + (s * b) * frame_.v - std::cos(theta) * frame_.w;
    dir = g / glm::length(g);
    return true;
  }

  std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const override {
    const glm::dvec3 p = worldPoint - frame_.e;
    const double x = glm::dot(p, frame_.u), y = glm::dot(p, frame_.v), z = glm::dot(p, frame_.w);
    const double lateral = std::hypot(x, y);
    if (lateral == 0 && z == 0) return std::nullopt;
    const double theta = std::atan2(lateral, -z);
    if (theta > halfFov_) return std::nullopt;
    if (lateral == 0) return glm::dvec2(cx_, cy_);
    const double rho = theta / halfFov_;
    return glm::dvec2(cx_ + radius_ * rho * x / lateral, cy_ - radius_ * rho * y / lateral);
  }

  ViewVolume viewVolume(double nearDist, double farDist) const override {
    return ViewVolume::allSpace(frame_.e, frame_.u, frame_.v, frame_.w, nearDist, farDist);
  }

 protected:
  void describeExtra(CameraDescription& c) const override {
    c.fisheye = FisheyeProjection{params_.fisheyeFovDeg, glm::dvec2(cx_, cy_), radius_};
    c.pixelAspectRatio = 1.0;  // the angle grows with the distance in pixels, alike on both axes
  }

 private:
  double halfFov_ = 0, radius_ = 1, cx_ = 0, cy_ = 0;
};

const ParamSpec kFisheyeFov{"fisheye_fov",
                            ParamKind::Number,
                            "degrees",
                            "Full field of view of the image circle",
                            nullptr,
                            {0.0, 360.0, true, false},
                            {},
                            {},
                            {},
                            fieldAccess<&CameraParams::fisheyeFovDeg>()};

std::unique_ptr<CameraBase> makeFisheyeCamera(const CameraParams& p,
                                              const glm::dvec3& renderOrigin) {
  return std::make_unique<FisheyeCamera>(p, renderOrigin);
}

}  // namespace

const CameraModel& fisheyeModel() {
  static const CameraModel m{"fisheye", "equidistant fisheye: angle from the axis ~ radius",
                             makeFisheyeCamera,
                             joinParamSpecs({commonParamSpecs(), {&kFisheyeFov}})};
  return m;
}

}  // namespace aperture
