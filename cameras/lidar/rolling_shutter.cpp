#include "cameras/lidar/rolling_shutter.h"

#include <cmath>
#include <vector>

#include "core/util/error.h"

namespace aperture {

namespace {

// A row's motion in render space: p' = rotation · p + shift (world motion
// worldFromSensor(t_i) · worldFromSensor(t_0)⁻¹ moved to render coordinates).
struct RowMotion {
  bool still = true;  ///< the row's time is the frame's start: its rays are the base camera's
  glm::dmat3 rotation{1.0};
  glm::dvec3 shift{0.0};
};

class RollingShutterCamera : public Camera {
 public:
  RollingShutterCamera(std::shared_ptr<const Camera> base, std::vector<RowMotion> rows)
      : base_(std::move(base)), rows_(std::move(rows)) {
    for (const RowMotion& r : rows_) moving_ = moving_ || !r.still;
  }

  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    base_->generate(req, out, valid);
    if (!moving_) return;
    for (int k = 0; k < req.lanes(); ++k) {
      const int row = req.pixel(k).row;
      if (row < 0 || row >= int(rows_.size()) || rows_[size_t(row)].still) continue;
      const RowMotion& m = rows_[size_t(row)];
      const glm::dvec3 o = m.rotation * glm::dvec3(out.orgX[k], out.orgY[k], out.orgZ[k]) + m.shift;
      const glm::dvec3 d =
          glm::normalize(m.rotation * glm::dvec3(out.dirX[k], out.dirY[k], out.dirZ[k]));
      out.orgX[k] = float(o.x);
      out.orgY[k] = float(o.y);
      out.orgZ[k] = float(o.z);
      if (std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z)) {
        out.dirX[k] = float(d.x);
        out.dirY[k] = float(d.y);
        out.dirZ[k] = float(d.z);
      }
    }
  }
  glm::vec3 renderEye() const override { return base_->renderEye(); }
  glm::vec3 viewAxis() const override { return base_->viewAxis(); }
  CameraDescription describe() const override { return described(base_->describe()); }
  CameraDescription describeWithoutCounts() const override {
    return described(base_->describeWithoutCounts());
  }
  WorldView worldView() const override { return base_->worldView(); }
  bool stochastic() const override { return base_->stochastic(); }
  std::optional<glm::dvec2> project(const glm::dvec3& worldPoint) const override {
    return base_->project(worldPoint);
  }
  bool centreRayAt(double x, double y, glm::dvec3& renderOrg, glm::dvec3& dir) const override {
    if (!base_->centreRayAt(x, y, renderOrg, dir)) return false;
    const int row = int(std::floor(y));
    if (row >= 0 && row < int(rows_.size()) && !rows_[size_t(row)].still) {
      const RowMotion& m = rows_[size_t(row)];
      renderOrg = m.rotation * renderOrg + m.shift;
      dir = glm::normalize(m.rotation * dir);
    }
    return true;
  }
  // Moving rows start from different points: no shared origin, so no coverage mask either.
  std::optional<glm::vec3> sharedRayOrigin() const override {
    return moving_ ? std::nullopt : base_->sharedRayOrigin();
  }
  std::optional<LensBlockBounds> lensBlockBounds() const override {
    return moving_ ? std::nullopt : base_->lensBlockBounds();
  }

 private:
  CameraDescription described(CameraDescription d) const {
    if (moving_) d.ndcFromWorld.reset();  // no single projection maps every row
    return d;
  }

  std::shared_ptr<const Camera> base_;
  std::vector<RowMotion> rows_;
  bool moving_ = false;
};

}  // namespace

void checkRollingShutter(const Trajectory& trajectory, int64_t frameStartNs,
                         double rowReadoutSeconds, int height) {
  if (!(rowReadoutSeconds >= 0) || !std::isfinite(rowReadoutSeconds))
    throw Error(cat("--rolling-shutter: the row readout time must be ≥ 0 seconds, not ",
                    rowReadoutSeconds));
  if (height <= 0) throw Error(cat("rolling shutter: image height ", height, " is not positive"));
  const int64_t rowNs = std::llround(rowReadoutSeconds * 1e9);
  const int64_t lastNs = frameStartNs + int64_t(height - 1) * rowNs;
  for (int64_t t : {frameStartNs, lastNs})
    if (!trajectory.covers(t))
      throw Error(cat("rolling shutter: row time ", formatTimeNs(t),
                      " s lies outside the trajectory ", trajectory.source(), " (",
                      formatTimeNs(trajectory.startNs()), " to ", formatTimeNs(trajectory.endNs()),
                      " s)"));
}

std::shared_ptr<const Camera> rollingShutterCamera(std::shared_ptr<const Camera> base,
                                                   const Trajectory& trajectory,
                                                   int64_t frameStartNs, double rowReadoutSeconds,
                                                   int height, const glm::dvec3& renderOrigin) {
  if (!base) throw Error("rolling shutter: no camera to read out");
  checkRollingShutter(trajectory, frameStartNs, rowReadoutSeconds, height);
  const int64_t rowNs = std::llround(rowReadoutSeconds * 1e9);
  const Pose start = trajectory.at(frameStartNs);
  const Pose startInverse = start.inverse();
  std::vector<RowMotion> rows(static_cast<size_t>(height));
  for (int i = 0; i < height; ++i) {
    const int64_t t = frameStartNs + int64_t(i) * rowNs;
    if (t == frameStartNs || trajectory.isStatic()) continue;
    const Pose motion = trajectory.at(t) * startInverse;
    RowMotion& r = rows[size_t(i)];
    r.still = false;
    r.rotation = glm::mat3_cast(motion.rotation);
    // p_world' = R p_world + t with p_world = p_render + a: p_render' = R p_render + (R a + t − a).
    r.shift = r.rotation * renderOrigin + motion.translation - renderOrigin;
  }
  return std::make_shared<RollingShutterCamera>(std::move(base), std::move(rows));
}

}  // namespace aperture
