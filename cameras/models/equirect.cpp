// Equirectangular panorama: longitude along the columns, latitude along the rows.
//
// Raster position (x, y) (pixel (i, j) centre at (j + ½, i + ½)), image W x H pixels,
// longitude range [lon0, lon1] and latitude range [lat0, lat1] (degrees, in radians below):
//   lon = lon0 + (x / W)·(lon1 − lon0)          (left edge lon0, right edge lon1)
//   lat = lat1 − (y / H)·(lat1 − lat0)          (top edge lat1, bottom edge lat0)
//   dir = cos(lat)·sin(lon)·U + sin(lat)·V − cos(lat)·cos(lon)·W
// so (lon, lat) = (0, 0) looks along −W, lon = +90° along +U, lat = +90° along +V. Origin e.
#include <cmath>
#include <vector>

#include "cameras/models/camera_models.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "core/util/vector_kernel.h"

namespace aperture {

namespace {

/// What the pixel-centre kernel needs: the camera's sines and cosines of the centres'
/// longitudes (per column) and latitudes (per row), the frame and the image size.
struct EquirectCentres {
  const double *sinLon, *cosLon, *sinLat, *cosLat;
  glm::dvec3 u, v, w;
  int width, height;
};

/// A kBW x kBH block of rays through pixel centres, rayAt() term by term from the tabulated
/// sines and cosines (the same libm calls on the same arguments, made once per column and
/// row by the camera): g = (cos lat·sin lon)·U + sin lat·V − (cos lat·cos lon)·W, g / |g|.
template <int kBW, int kBH>
void equirectCentres(const EquirectCentres& c, const glm::dvec3& eye, int x0, int y0, RayLanes& out,
                     int* valid) {
  constexpr int kLanes = kBW * kBH;
  alignas(64) float dx[kLanes], dy[kLanes], dz[kLanes];
  alignas(64) double laneSinLon[kLanes], laneCosLat[kLanes], laneCosLon[kLanes], laneSinLat[kLanes];
  spreadOverLanes<kBW, kBH>(c.sinLon + x0, c.cosLat + y0, laneSinLon, laneCosLat);
  spreadOverLanes<kBW, kBH>(c.cosLon + x0, c.sinLat + y0, laneCosLon, laneSinLat);
  APERTURE_LANE_LOOP
  for (int k = 0; k < kLanes; ++k) {
    const double a = laneCosLat[k] * laneSinLon[k], b = laneCosLat[k] * laneCosLon[k];
    const double sinLat = laneSinLat[k];
    const double gx = (a * c.u.x + sinLat * c.v.x) - b * c.w.x;
    const double gy = (a * c.u.y + sinLat * c.v.y) - b * c.w.y;
    const double gz = (a * c.u.z + sinLat * c.v.z) - b * c.w.z;
    const double length = std::sqrt((gx * gx + gy * gy) + gz * gz);
    dx[k] = float(gx / length);
    dy[k] = float(gy / length);
    dz[k] = float(gz / length);
  }
  writeBlockLanesFromOrigin<kLanes>(out, eye, dx, dy, dz);
  writeBlockInImage<kBW, kBH>(x0, y0, c.width, c.height, valid);
}

class EquirectCamera final : public PacketCamera<EquirectCamera> {
 public:
  EquirectCamera(const CameraParams& p, const glm::dvec3& renderOrigin)
      : PacketCamera(p, renderOrigin, "equirect") {
    rejectShift();
    const glm::dvec2 lon = p.longitudeRangeDeg, lat = p.latitudeRangeDeg;
    // Each end lies in its spec's range (checked by makeCamera); the order and the span of a
    // range are not ranges of its ends.
    if (!(lon.x < lon.y && lon.y - lon.x <= 360))
      throw Error(cat("camera: longitude range [", lon.x, ", ", lon.y,
                      "] degrees must be increasing and span at most 360"));
    if (!(lat.x < lat.y))
      throw Error(
          cat("camera: latitude range [", lat.x, ", ", lat.y, "] degrees must be increasing"));
    lon0_ = lon.x * kRadPerDeg;
    lonPerPixel_ = (lon.y - lon.x) * kRadPerDeg / width_;
    lat1_ = lat.y * kRadPerDeg;
    latPerPixel_ = (lat.y - lat.x) * kRadPerDeg / height_;
    // The pixel centres' sines and cosines, as rayAt() computes them; the tables run past the
    // right and bottom edges by a block, for the lanes of blocks that cross them.
    constexpr int kPast = 3;
    for (int j = 0; j < width_ + kPast; ++j) {
      const double lonJ = lon0_ + (double(j) + 0.5) * lonPerPixel_;
      sinLon_.push_back(std::sin(lonJ));
      cosLon_.push_back(std::cos(lonJ));
    }
    for (int i = 0; i < height_ + kPast; ++i) {
      const double latI = lat1_ - (double(i) + 0.5) * latPerPixel_;
      sinLat_.push_back(std::sin(latI));
      cosLat_.push_back(std::cos(latI));
    }
  }

  /// Rays through pixel centres (every sample at 1 spp, the centre ray at any spp) in the
  /// frame loop's block shapes take the tabulated kernel; everything else the packet loop.
  /// Every ray starts at the eye, at tnear 0.
  std::optional<glm::vec3> sharedRayOrigin() const override { return renderEye_; }

  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    if (spp_ == 1 || req.centreRay()) {
      const EquirectCentres c{sinLon_.data(), cosLon_.data(), sinLat_.data(),
                              cosLat_.data(), frame_.u,       frame_.v,
                              frame_.w,       width_,         height_};
      const bool done = withBlockShape(req.blockW, req.blockH, [&](auto bw, auto bh) {
        constexpr int kBW = decltype(bw)::value, kBH = decltype(bh)::value;
        runKernel<&equirectCentres<kBW, kBH>>(c, renderEyeD_, req.x0, req.y0, out, valid);
      });
      if (done) return;
    }
    PacketCamera::generate(req, out, valid);
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
  /// sin and cos of the longitude of column j's centre and of the latitude of row i's centre
  std::vector<double> sinLon_, cosLon_, sinLat_, cosLat_;
};

const ParamSpec kLon =
    ParamSpec("lon", ParamKind::Vec2, fieldAccess<&CameraParams::longitudeRangeDeg>())
        .withUnit("degrees")
        .withHelp("Longitude range MIN,MAX (columns)")
        .withRange(ParamRange::closed(-360.0, 360.0));
const ParamSpec kLat =
    ParamSpec("lat", ParamKind::Vec2, fieldAccess<&CameraParams::latitudeRangeDeg>())
        .withUnit("degrees")
        .withHelp("Latitude range MIN,MAX (rows)")
        .withRange(ParamRange::closed(-90.0, 90.0));

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
