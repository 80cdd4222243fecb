// The geometry AOVs (Z, T, N, P, primID, geomID) come from the centre ray of each pixel (pixel
// centre (j + ½, i + ½), lens centre) at every spp, so they do not move when spp changes; colour
// averages the stratified samples. Checked on the Stanford bunny with its reference view.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "tests/camera_support.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

using namespace aperture;

namespace {

constexpr AovMask kGeometry =
    kAovDepth | kAovDistance | kAovNormal | kAovPosition | kAovPrimId | kAovGeomId;

// The bunny's reference view (../shared/meshes/README.md), one camera per family: pinhole,
// thin lens (focused on the bunny, so its centre ray differs from the pinhole's), parallel and
// a panorama with pixels outside its circle.
struct ViewCase {
  const char* name;
  const char* flags;
};
const ViewCase kViews[] = {
    {"perspective", "--camera perspective --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --fov 30"},
    {"thinlens",
     "--camera thinlens --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --fov 30 --aperture 0.01 "
     "--focus 0.33"},
    {"orthographic",
     "--camera orthographic --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --viewport 0.19,0.19"},
    {"fisheye", "--camera fisheye --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --fisheye-fov 40"},
};
constexpr int kSize = 72;

CameraParams viewParams(const ViewCase& v, int spp) {
  return test::cameraParamsFromFlags(std::string(v.flags) + " --size " + std::to_string(kSize) +
                                     "," + std::to_string(kSize) + " --spp " + std::to_string(spp));
}

/// The bunny and its scene, loaded once for the whole file.
const test::Loaded& bunny(const std::string& path) {
  static const test::Loaded loaded = test::load(path);
  return loaded;
}

Framebuffer renderWith(const Scene& scene, const Camera& cam, int spp, AovMask aovs,
                       RenderStats* stats = nullptr) {
  Framebuffer fb(kSize, kSize, aovs);
  RenderSettings rs;
  rs.spp = spp;
  const RenderStats s = renderImage(scene, cam, rs, fb);
  if (stats) *stats = s;
  return fb;
}

/// The geometry AOVs of fb alone (colour dropped), for bit comparisons with differingAovs.
Framebuffer geometryOf(const Framebuffer& fb) {
  Framebuffer g(fb.width, fb.height, kGeometry);
  g.depth = fb.depth, g.distance = fb.distance, g.normal = fb.normal;
  g.position = fb.position, g.primId = fb.primId, g.geomId = fb.geomId;
  return g;
}

size_t hitCount(const Framebuffer& fb) {
  size_t n = 0;
  for (uint32_t id : fb.geomId) n += id != kInvalidId;
  return n;
}

/// The pre-issue-10 behaviour, generated explicitly: the centre-ray request is answered with
/// stratified sample 0 (what the geometry AOVs used to come from).
class SampleZeroAsCentre final : public Camera {
 public:
  explicit SampleZeroAsCentre(const Camera& inner) : inner_(inner) {}
  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    PacketRequest r = req;
    if (r.centreRay()) r.sample = 0;
    inner_.generate(r, out, valid);
  }
  glm::vec3 renderEye() const override { return inner_.renderEye(); }
  glm::vec3 viewAxis() const override { return inner_.viewAxis(); }
  CameraDescription describe() const override { return inner_.describe(); }
  bool stochastic() const override { return inner_.stochastic(); }
  std::optional<glm::dvec2> project(const glm::dvec3& p) const override {
    return inner_.project(p);
  }
  bool centreRayAt(double x, double y, glm::dvec3& o, glm::dvec3& d) const override {
    return inner_.centreRayAt(x, y, o, d);
  }

 private:
  const Camera& inner_;
};

}  // namespace

TEST(CentreRay, GeometryAovsAreBitIdenticalAtEverySppOnTheBunny) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const Scene& scene = *bunny(path).scene;
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const Framebuffer one = test::render(scene, viewParams(v, 1), kGeometry | kAovColor);
    ASSERT_GT(hitCount(one), size_t(kSize * kSize / 8)) << "the bunny must fill the view";
    ASSERT_LT(hitCount(one), size_t(kSize * kSize)) << "and leave misses around it";
    for (int spp : {4, 16}) {
      const Framebuffer withColor = test::render(scene, viewParams(v, spp), kGeometry | kAovColor);
      const Framebuffer alone = test::render(scene, viewParams(v, spp), kGeometry);
      EXPECT_EQ(test::differingAovs(geometryOf(withColor), geometryOf(one)), "") << spp << " spp";
      EXPECT_EQ(test::differingAovs(alone, geometryOf(one)), "") << spp << " spp, no colour";
      // Colour still averages the samples: antialiased edges (and the lens blur) change it.
      EXPECT_NE(
          std::memcmp(withColor.rgba.data(), one.rgba.data(), one.rgba.size() * sizeof(float)), 0)
          << spp << " spp colour equals 1 spp colour";
    }
  }
}

// The test above can fail: geometry taken from stratified sample 0 (the old rule) moves with
// spp. At 16 spp sample 0 lies in the top-left stratum, up to (0.375, 0.375) px from the centre.
TEST(CentreRay, GeometryFromStratifiedSampleZeroWouldDiffer) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const Scene& scene = *bunny(path).scene;
  for (const ViewCase& v : kViews) {
    SCOPED_TRACE(v.name);
    const auto cam = makeCamera(viewParams(v, 16), scene.renderOrigin());
    const Framebuffer centre = renderWith(scene, *cam, 16, kGeometry);
    const Framebuffer sampleZero = renderWith(scene, SampleZeroAsCentre(*cam), 16, kGeometry);
    size_t depthDiffers = 0, primDiffers = 0;
    for (size_t px = 0; px < centre.pixelCount(); ++px) {
      depthDiffers += std::memcmp(&centre.depth[px], &sampleZero.depth[px], sizeof(float)) != 0;
      primDiffers += centre.primId[px] != sampleZero.primId[px];
    }
    EXPECT_GT(depthDiffers, hitCount(centre) / 2) << "Z would move on most hit pixels";
    EXPECT_GT(primDiffers, size_t(0)) << "and primID on some";
  }
}

// The centre-ray packets are ray(j + ½, i + ½, ½, ½) of the scalar path for every model and
// packet shape at spp 16 (the perspective pinhole through its vectorised path), equal sample 0
// at spp 1, and are neither sample 0 at spp 16 nor the pixel corner's ray (j, i).
TEST(CentreRay, PacketsAreThePixelCentreAndLensCentreRays) {
  for (CameraParams p : test::everyCamera()) {
    p.width = 13, p.height = 7;  // tail lanes right and bottom
    for (int spp : {1, 16}) {
      p.spp = spp;
      SCOPED_TRACE(p.type + " spp " + std::to_string(spp));
      const auto cam = makeCameraModel(p, glm::dvec3(-2.0, 0.5, 1.5));
      for (int width : {1, 4, 8, 16}) {
        int bw, bh;
        test::blockShape(width, bw, bh);
        int notSampleZero = 0, notCorner = 0, lanes = 0;
        for (int y0 = 0; y0 < p.height; y0 += bh)
          for (int x0 = 0; x0 < p.width; x0 += bw) {
            test::PacketBuffer centre(width), zero(width);
            int vc[16], vz[16];
            const PacketRequest req{x0, y0, bw, bh, PacketRequest::kCentreRay};
            cam->generate(req, centre.lanes(), vc);
            cam->generate({x0, y0, bw, bh, 0}, zero.lanes(), vz);
            for (int k = 0; k < width; ++k) {
              const int i = req.pixel(k).row, j = req.pixel(k).column;
              if (!req.inImage(k, p.width, p.height)) {
                EXPECT_EQ(vc[k], 0) << "lane outside the image";
                continue;
              }
              glm::dvec3 org, dir, cornerOrg, cornerDir;
              const bool has = cam->ray(j + 0.5, i + 0.5, 0.5, 0.5, org, dir);
              cam->ray(j, i, 0.5, 0.5, cornerOrg, cornerDir);
              const RayLanes& l = centre.lanes();
              const glm::vec3 o(l.orgX[k], l.orgY[k], l.orgZ[k]),
                  d(l.dirX[k], l.dirY[k], l.dirZ[k]);
              ASSERT_EQ(vc[k], has ? -1 : 0) << "pixel " << i << "," << j;
              if (!has) continue;
              ASSERT_EQ(o, glm::vec3(org)) << "pixel " << i << "," << j;
              ASSERT_EQ(d, glm::vec3(dir)) << "pixel " << i << "," << j;
              const RayLanes& z = zero.lanes();
              const glm::vec3 dz(z.dirX[k], z.dirY[k], z.dirZ[k]),
                  oz(z.orgX[k], z.orgY[k], z.orgZ[k]);
              notSampleZero += dz != d || oz != o;
              notCorner += glm::vec3(cornerDir) != d || glm::vec3(cornerOrg) != o;
              ++lanes;
            }
          }
        ASSERT_GT(lanes, 0);
        if (spp == 1)
          EXPECT_EQ(notSampleZero, 0) << "at spp 1 sample 0 is the centre ray";
        else
          EXPECT_EQ(notSampleZero, lanes) << "at spp 16 sample 0 is never the centre ray";
        EXPECT_EQ(notCorner, lanes) << "the corner convention would be caught";
      }
    }
  }
}

// Rays traced, counted independently through the scalar path: the camera's rays of every
// stratified sample for colour, plus one centre ray per pixel for the geometry AOVs (none extra
// at spp 1); without colour only the centre rays. The fisheye has pixels without a ray.
TEST(CentreRay, RayCountsAreOneCentreRayPlusTheColourSamples) {
  APERTURE_REQUIRE_SHARED_MESH(path, "stanford/bun_zipper.ply");
  const Scene& scene = *bunny(path).scene;
  for (const int view : {0, 3}) {  // perspective, fisheye
    const ViewCase& v = kViews[view];
    for (int spp : {1, 16}) {
      SCOPED_TRACE(std::string(v.name) + " spp " + std::to_string(spp));
      const auto cam = makeCameraModel(viewParams(v, spp), scene.renderOrigin());
      uint64_t centreRays = 0, sampleRays = 0;
      glm::dvec3 org, dir;
      for (int i = 0; i < kSize; ++i)
        for (int j = 0; j < kSize; ++j) {
          centreRays += cam->ray(j + 0.5, i + 0.5, 0.5, 0.5, org, dir);
          for (int s = 0; s < spp; ++s) {
            double x, y;
            cam->samplePosition(i, j, s, x, y);
            sampleRays += cam->ray(x, y, 0.5, 0.5, org, dir);
          }
        }
      if (view == 0) {
        EXPECT_EQ(centreRays, uint64_t(kSize * kSize));
        EXPECT_EQ(sampleRays, uint64_t(spp) * kSize * kSize);
      } else {
        EXPECT_LT(centreRays, uint64_t(kSize * kSize)) << "the fisheye's corners have no ray";
      }
      RenderStats geometryOnly, colorAndDepth, colorOnly;
      renderWith(scene, *cam, spp, kAovDepth | kAovNormal, &geometryOnly);
      renderWith(scene, *cam, spp, kAovColor | kAovDepth, &colorAndDepth);
      renderWith(scene, *cam, spp, kAovColor, &colorOnly);
      EXPECT_EQ(geometryOnly.raysTraced, centreRays);
      EXPECT_EQ(colorAndDepth.raysTraced, sampleRays + (spp > 1 ? centreRays : 0));
      EXPECT_EQ(colorOnly.raysTraced, sampleRays);
      EXPECT_EQ(geometryOnly.raysSkipped + colorAndDepth.raysSkipped, 0u);
    }
  }
}
