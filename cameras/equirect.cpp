// Equirectangular panorama: longitude along the columns, latitude along the rows.
//
// Raster position (x, y) (pixel (i, j) centre at (j + ½, i + ½)), image W x H pixels,
// longitude range [lon0, lon1] and latitude range [lat0, lat1] (degrees, in radians below):
//   lon = lon0 + (x / W)·(lon1 − lon0)          (left edge lon0, right edge lon1)
//   lat = lat1 − (y / H)·(lat1 − lat0)          (top edge lat1, bottom edge lat0)
//   dir = cos(lat)·sin(lon)·U + sin(lat)·V − cos(lat)·cos(lon)·W
// so (lon, lat) = (0, 0) looks along −W, lon = +90° along +U, lat = +90° along +V. Origin e.
#include <cmath>

#include "cameras/models.h"
#include "core/error.h"
#include "core/units.h"

namespace aperture {

namespace {

class EquirectCamera final : public PacketCamera<EquirectCamera> {
 public:
  EquirectCamera(const CameraParams& p, const glm::dvec3& renderOrigin)
      : PacketCamera(p, renderOrigin, "equirect") {
    rejectShift();
    const glm::dvec2 lon = p.longitudeRangeDeg, lat = p.latitudeRangeDeg;
    if (!(std::isfinite(lon.x) && std::isfinite(lon.y) && lon.x < lon.y && lon.y - lon.x <= 360))
      throw Error(cat("camera: longitude range [", lon.x, ", ", lon.y,
                      "] degrees must be increasing and span at most 360"));
    if (!(lat.x >= -90 && lat.x < lat.y && lat.y <= 90))
      throw Error(cat("camera: latitude range [", lat.x, ", ", lat.y,
                      "] degrees must be increasing within [-90, 90]"));
    lon0_ = lon.x * kRadPerDeg;
    lonPerPixel_ = (lon.y - lon.x) * kRadPerDeg / width_;
    lat1_ = lat.y * kRadPerDeg;
    latPerPixel_ = (lat.y - lat.x) * kRadPerDeg / height_;
  }

  bool usesLens() const { return false; }
  bool rayAt(double x, double y, double, double, glm::dvec3& org, glm::dvec3& dir) const {
    const double lon = lon0_ + x * lonPerPixel_, lat = lat1_ - y * latPerPixel_;
    const double c = std::cos(lat);
    const glm::dvec3 g =
        (c * std::sin(lon)) * frame_.u + std::sin(lat) * frame_.v - (c * std::cos(lon)) * frame_.w;
    org = renderEyeD_;
    dir = g / glm::length(g);
    return true;
  }

  std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const override {
    const glm::dvec3 p = worldPoint - frame_.e;
    const double x = glm::dot(p, frame_.u), y = glm::dot(p, frame_.v), z = glm::dot(p, frame_.w);
    if (x == 0 && y == 0 && z == 0) return std::nullopt;
    double lon = std::atan2(x, -z);
    const double lat = std::atan2(y, std::hypot(x, z));
    // Pick the turn of the longitude that falls in (or nearest after) the range.
    constexpr double kTwoPi = 6.283185307179586477;
    while (lon < lon0_) lon += kTwoPi;
    while (lon - kTwoPi >= lon0_) lon -= kTwoPi;
    return glm::dvec2((lon - lon0_) / lonPerPixel_, (lat1_ - lat) / latPerPixel_);
  }

  ViewVolume viewVolume(double nearDist, double farDist) const override {
    return ViewVolume::allSpace(frame_.e, frame_.u, frame_.v, frame_.w, nearDist, farDist);
  }

 protected:
  void describeExtra(CameraDescription& c) const override {
    const glm::dvec2 lon = params_.longitudeRangeDeg, lat = params_.latitudeRangeDeg;
    c.equirect = EquirectProjection{lon, lat};
    // Shown with square degrees: a pixel is (lon1 − lon0) / W degrees wide, (lat1 − lat0) / H
    // degrees high.
    c.pixelAspectRatio = ((lon.y - lon.x) / width_) / ((lat.y - lat.x) / height_);
  }

 private:
  double lon0_ = 0, lonPerPixel_ = 0, lat1_ = 0, latPerPixel_ = 0;  // radians
};

const ParamSpec kLon{"lon",     ParamKind::Vec2,
                     "degrees", "Longitude range MIN,MAX (columns)",
                     nullptr,   {-360.0, 360.0},
                     {},        {},
                     {},        fieldAccess<&CameraParams::longitudeRangeDeg>()};
const ParamSpec kLat{"lat",     ParamKind::Vec2,
                     "degrees", "Latitude range MIN,MAX (rows)",
                     nullptr,   {-90.0, 90.0},
                     {},        {},
                     {},        fieldAccess<&CameraParams::latitudeRangeDeg>()};

std::unique_ptr<CameraBase> makeEquirectCamera(const CameraParams& p,
                                               const glm::dvec3& renderOrigin) {
  return std::make_unique<EquirectCamera>(p, renderOrigin);
}

}  // namespace

const CameraModel& equirectModel() {
  static const CameraModel m{"equirect", "panorama: longitude along the columns, latitude down",
                             makeEquirectCamera,
                             joinParamSpecs({commonParamSpecs(), {&kLon, &kLat}})};
  return m;
}

}  // namespace aperture
