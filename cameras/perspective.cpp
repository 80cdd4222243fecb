// Perspective camera of the lecture: origin e, direction u·U + v·V − d·W, normalised.
#include "cameras/models.h"

namespace aperture {

namespace {

class PerspectiveCamera final : public FrameCamera {
 public:
  PerspectiveCamera(const CameraParams& p, const glm::dvec3& renderOrigin)
      : FrameCamera(p, renderOrigin, "perspective"), org_(frame_.e - renderOrigin) {}

  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    const int lanes = req.blockW * req.blockH;
    for (int k = 0; k < lanes; ++k) {
      const int i = req.y0 + k / req.blockW, j = req.x0 + k % req.blockW;
      valid[k] = (i < height_ && j < width_) ? -1 : 0;
      double x, y, u, v;
      samplePosition(i, j, req.sample, x, y);
      rasterToPlane(x, y, u, v);
      const glm::dvec3 dir = u * frame_.u + v * frame_.v - d_ * frame_.w;
      setLane(out, k, org_, dir / glm::length(dir));
    }
  }

 protected:
  glm::dmat4 ndcFromCamera() const override {
    // x_ndc = (d x / −z) / vw + ½, y_ndc = ½ − (d y / −z) / vh, after dividing by w = −z;
    // the third row gives z_ndc = 1 / Z. GLM: m[column][row].
    glm::dmat4 m(0.0);
    m[0][0] = d_ / vw_;
    m[2][0] = -0.5;
    m[1][1] = -d_ / vh_;
    m[2][1] = -0.5;
    m[3][2] = 1.0;
    m[2][3] = -1.0;
    return m;
  }

 private:
  glm::dvec3 org_;
};

}  // namespace

std::unique_ptr<Camera> makePerspectiveCamera(const CameraParams& p,
                                              const glm::dvec3& renderOrigin) {
  return std::make_unique<PerspectiveCamera>(p, renderOrigin);
}

}  // namespace aperture
