// Numerics of bad input and determinism: non-finite vertices, camera parameters and rays; the same
// command three times. Part of the numerics tests (issue 5): each test checks a closed form or an
// independent path; the world-space float32 mode's errors are measured and printed
// (docs/numerics.md records them), not asserted.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/engine/layers.h"
#include "core/engine/packet.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/exr/exr.h"
#include "core/mesh/mesh.h"
#include "core/queries/trace.h"
#include "core/util/error.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace {

using namespace aperture::test;

// --- Non-finite input ------------------------------------------------------------------

TEST(NumericsNonFinite, NanAndInfVerticesAreDroppedAndCountedThroughTheRenderer) {
  const std::string dir = test::scratchDir();
  // Two quads facing +z: the left one (x < 0) uses a NaN and an Inf vertex.
  test::writeFile(dir + "/bad.ply",
                  "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                  "end_header\n"
                  "-2 -1 0\n0 -1 0\nnan 1 0\n-2 1 inf\n"
                  "0 -1 0\n2 -1 0\n2 1 0\n0 1 0\n"
                  "3 0 1 2\n3 0 2 3\n3 4 5 6\n3 4 6 7\n");
  std::string out;
  const std::string cmd = test::apertureBinary() + " render --mesh " + dir +
                          "/bad.ply --eye 0,0,6 --at 0,0,0 --size 40,20 --fov 40 --aov "
                          "depth,primid --out " +
                          dir + "/bad.exr";
  ASSERT_EQ(test::runCommand(cmd, &out), 0) << out;
  EXPECT_NE(out.find("2 non-finite vertices, 2 triangles dropped"), std::string::npos) << out;
  const Framebuffer fb = readExr(dir + "/bad.exr");
  size_t left = 0, right = 0;
  for (int i = 0; i < fb.height; ++i)
    for (int j = 0; j < fb.width; ++j) {
      const size_t px = size_t(i) * size_t(fb.width) + size_t(j);
      ASSERT_FALSE(std::isnan(fb.depth[px]));
      if (fb.primId[px] == kInvalidId) continue;
      EXPECT_LT(fb.primId[px], 2u);  // the two finite triangles, renumbered 0 and 1
      (j < fb.width / 2 ? left : right)++;
    }
  EXPECT_EQ(left, 0u);
  EXPECT_GT(right, 0u);
}

TEST(NumericsNonFinite, NonFiniteCameraParametersAreErrors) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto base = [] {
    CameraParams p;
    p.eye = glm::dvec3(0, 0, 5);
    p.at = glm::dvec3(0.0);
    p.width = 8;
    p.height = 8;
    return p;
  };
  std::vector<CameraParams> bad;
  for (double x : {nan, inf, -inf}) {
    CameraParams p = base();
    p.eye.y = x;
    bad.push_back(p);
    p = base();
    p.at = glm::dvec3(x, 0, 0);
    bad.push_back(p);
    p = base();
    p.up = glm::dvec3(0, x, 0);
    bad.push_back(p);
    p = base();
    p.fovDeg = x;
    bad.push_back(p);
    p = base();
    p.d = x;
    p.viewport = glm::dvec2(1, 1);
    bad.push_back(p);
    p = base();
    p.viewport = glm::dvec2(x, 1);
    bad.push_back(p);
    p = base();
    p.shift = glm::dvec2(0, x);
    bad.push_back(p);
    p = base();
    p.type = "thinlens";
    p.apertureRadius = x;
    bad.push_back(p);
    p = base();
    p.type = "thinlens";
    p.apertureRadius = 0.1;
    p.focusDistance = x;
    bad.push_back(p);
    p = base();
    p.type = "oblique";
    p.viewport = glm::dvec2(1, 1);
    p.obliqueAnglesDeg = glm::dvec2(x, 0);
    bad.push_back(p);
  }
  for (size_t k = 0; k < bad.size(); ++k) EXPECT_THROW(makeCamera(bad[k]), Error) << k;
  // A non-finite render origin (a broken anchor) is an error too.
  EXPECT_THROW(makeCamera(base(), glm::dvec3(nan, 0, 0)), Error);
  // And on the command line.
  std::string out;
  EXPECT_NE(test::runCommand(test::apertureBinary() + " render --eye nan,0,5 --size 8,8 --out " +
                                 test::scratchDir() + "/x.exr",
                             &out),
            0);
  EXPECT_NE(out.find("--eye"), std::string::npos) << out;
}

/// A camera whose rays are those of a real one except that some lanes get a NaN or an Inf
/// (in the direction or the origin): the frame loop must not trace them.
class PoisonedCamera final : public Camera {
 public:
  explicit PoisonedCamera(std::unique_ptr<Camera> inner) : inner_(std::move(inner)) {}
  static bool poisoned(int i, int j) { return (i * 7 + j * 3) % 5 == 0; }
  void generate(const PacketRequest& req, RayLanes& out, int* valid) const override {
    inner_->generate(req, out, valid);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    for (int k = 0; k < req.lanes(); ++k) {
      const int i = req.pixel(k).row, j = req.pixel(k).column;
      if (!poisoned(i, j)) continue;
      switch ((i + j) % 3) {
        case 0:
          out.dirX[k] = nan;
          break;
        case 1:
          out.orgZ[k] = -inf;
          break;
        default:
          out.dirZ[k] = inf;
          break;
      }
    }
  }
  glm::vec3 renderEye() const override { return inner_->renderEye(); }
  glm::vec3 viewAxis() const override { return inner_->viewAxis(); }
  CameraDescription describe() const override { return inner_->describe(); }
  bool stochastic() const override { return inner_->stochastic(); }
  std::optional<glm::dvec2> project(const glm::dvec3& p) const override {
    return inner_->project(p);
  }
  bool centreRayAt(double x, double y, glm::dvec3& o, glm::dvec3& d) const override {
    return inner_->centreRayAt(x, y, o, d);
  }

 private:
  std::unique_ptr<Camera> inner_;
};

TEST(NumericsNonFinite, NonFiniteRaysAreNeverTracedAndNeverReachTheFramebuffer) {
  const Loaded l = load("procedural:quad?size=100&z=0");
  CameraParams p;
  p.eye = glm::dvec3(0, 0, 4);
  p.at = glm::dvec3(0.0);
  p.width = 37;
  p.height = 23;
  for (int spp : {1, 4}) {
    p.spp = spp;
    for (int packet : {1, 4, 8, 16}) {
      const PoisonedCamera cam(makeCamera(p, l.scene->renderOrigin()));
      Framebuffer fb(p.width, p.height, parseAovList("all"));
      RenderSettings rs;
      rs.packetWidth = packet;
      rs.spp = spp;
      const RenderStats stats = renderImage(*l.scene, cam, rs, fb);
      size_t bad = 0;
      for (int i = 0; i < p.height; ++i)
        for (int j = 0; j < p.width; ++j) {
          const size_t px = size_t(i) * size_t(p.width) + size_t(j);
          if (!PoisonedCamera::poisoned(i, j)) {
            EXPECT_NE(fb.primId[px], kInvalidId);
            continue;
          }
          ++bad;
          EXPECT_EQ(fb.primId[px], kInvalidId);
          EXPECT_EQ(fb.geomId[px], kInvalidId);
          EXPECT_EQ(fb.depth[px], std::numeric_limits<float>::infinity());
          EXPECT_EQ(fb.distance[px], std::numeric_limits<float>::infinity());
          for (int c = 0; c < 4; ++c) EXPECT_EQ(fb.rgba[4 * px + size_t(c)], 0.0f);
          for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(fb.normal[3 * px + size_t(c)], 0.0f);
            EXPECT_EQ(fb.position[3 * px + size_t(c)], 0.0f);
          }
        }
      // Every colour sample, plus the centre ray of the geometry AOVs when spp > 1.
      const uint64_t raysPerPixel = spp > 1 ? uint64_t(spp) + 1 : 1;
      EXPECT_EQ(stats.raysSkipped, uint64_t(bad) * raysPerPixel);
      EXPECT_EQ(stats.raysTraced, uint64_t(fb.pixelCount() - bad) * raysPerPixel);
      for (float v : fb.rgba) EXPECT_TRUE(std::isfinite(v));
    }
  }
}

/// What Embree may be handed, written from its documentation (RTCRay, rtcIntersectNM) rather
/// than from core/engine/packet.h: an active lane holds a ray with finite origin and direction
/// within Embree's range and a segment 0 <= tnear <= tfar; an inactive lane has tfar < tnear, since
/// a device without native kernels of the packet's width traces it as a stream, mask ignored.
struct PacketAudit {
  static inline std::atomic<uint64_t> packets{0}, activeLanes{0}, inactiveLanes{0}, bad{0};
  static void reset() { packets = 0, activeLanes = 0, inactiveLanes = 0, bad = 0; }
  static bool embreeRay(const RayLanes& l, int k) {
    for (const float* c : {l.orgX, l.orgY, l.orgZ, l.dirX, l.dirY, l.dirZ})
      if (!std::isfinite(c[k]) || std::fabs(c[k]) > 1.844e18f) return false;
    return l.tnear[k] >= 0.0f && l.tnear[k] <= l.tfar[k];
  }
  static void observe(int width, const int* valid, const RayLanes& l) {
    ++packets;
    for (int k = 0; k < width; ++k) {
      if (valid[k] == -1) {
        ++activeLanes;
        bad += !embreeRay(l, k);
      } else {
        ++inactiveLanes;
        bad += valid[k] != 0 || !(l.tfar[k] < l.tnear[k]);
      }
    }
  }
  /// Observes every packet handed to Embree while alive.
  struct Scope {
    Scope() {
      reset();
      packetObserver = &observe;
    }
    ~Scope() { packetObserver = nullptr; }
  };
};

TEST(NumericsNonFinite, EveryPacketHandedToEmbreeHoldsOnlyValidRaysInItsActiveLanes) {
  // The poisoned camera's NaN and Inf lanes, at every packet width, with the centre-ray pass
  // (spp 4) and both layer methods: no active lane may hold them, and no inactive lane may be
  // one a ray stream would trace. Checked on the packets themselves, so on any CPU: only
  // Embree's emulated widths (rtcIntersect16 without AVX-512) trace what the mask leaves out.
  const Loaded l = load("procedural:quad?size=100&z=0");
  CameraParams p;
  p.eye = glm::dvec3(0, 0, 4);
  p.at = glm::dvec3(0.0);
  p.width = 37;
  p.height = 23;
  const LayerMethod method = defaultLayerMethod();
  for (LayerMethod layers : {LayerMethod::Filter, LayerMethod::Retrace})
    for (int spp : {1, 4})
      for (int packet : {1, 4, 8, 16}) {
        setLayerMethod(layers);
        p.spp = spp;
        const PoisonedCamera cam(makeCamera(p, l.scene->renderOrigin()));
        AovSet aovs = parseAovList("all");
        aovs.layers = 2;
        Framebuffer fb(p.width, p.height, aovs);
        RenderSettings rs;
        rs.packetWidth = packet;
        rs.spp = spp;
        const PacketAudit::Scope audit;
        renderImage(*l.scene, cam, rs, fb);
        EXPECT_GT(PacketAudit::packets.load(), 0u);
        EXPECT_GT(PacketAudit::activeLanes.load(), 0u);
        if (packet > 1) {
          EXPECT_GT(PacketAudit::inactiveLanes.load(), 0u);
        }
        EXPECT_EQ(PacketAudit::bad.load(), 0u)
            << "packet " << packet << ", spp " << spp << ", " << layerMethodName(layers);
      }
  setLayerMethod(method);
  // traceRays: bad rays beside good ones in every packet; the bad ones come back as misses.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<TraceRay> rays(37);
  for (size_t k = 0; k < rays.size(); ++k) {
    rays[k].org = glm::vec3(0.1f * float(k % 7), 0.0f, 4.0f);
    switch (k % 5) {
      case 1:
        rays[k].org.x = 1e30f;  // finite, past Embree's range
        break;
      case 2:
        rays[k].tnear = -1.0f;
        break;
      case 3:
        rays[k].tnear = 2.0f, rays[k].tfar = 1.0f;
        break;
      default:
        break;
    }
  }
  rays[4].dir.y = nan, rays[9].org.z = inf;
  for (int packet : {1, 4, 8, 16}) {
    const PacketAudit::Scope audit;
    const std::vector<TraceHit> hits = traceRays(*l.scene, rays, packet);
    EXPECT_EQ(PacketAudit::bad.load(), 0u) << "traceRays, packet " << packet;
    for (size_t k = 0; k < rays.size(); ++k) {
      const bool good = (k % 5 == 0 || k % 5 == 4) && k != 4 && k != 9;
      EXPECT_EQ(hits[k].hit(), good) << k << ", packet " << packet;
    }
  }
}

// --- Determinism -----------------------------------------------------------------------

TEST(NumericsDeterminism, TheSameRenderCommandThreeTimesGivesBitIdenticalPixels) {
  const std::string dir = test::scratchDir();
  std::vector<Framebuffer> runs;
  for (int k = 0; k < 3; ++k) {
    const std::string path = dir + "/run" + std::to_string(k) + ".exr";
    std::string out;
    ASSERT_EQ(test::runCommand(test::apertureBinary() +
                                   " render --mesh procedural:city --camera thinlens --aperture "
                                   "0.2 --focus 15 --spp 4 --eye 14,11,18 --at 0,1,0 --size "
                                   "96,64 --aov all --threads 2 --quiet --out " +
                                   path,
                               &out),
              0)
        << out;
    runs.push_back(readExr(path));
  }
  // The header holds the render time, so the files differ; the pixels must not.
  for (int k = 1; k < 3; ++k) {
    const Framebuffer &a = runs[0], &b = runs[size_t(k)];
    auto same = [](const auto& x, const auto& y) {
      return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
    };
    EXPECT_TRUE(same(a.rgba, b.rgba));
    EXPECT_TRUE(same(a.depth, b.depth));
    EXPECT_TRUE(same(a.distance, b.distance));
    EXPECT_TRUE(same(a.normal, b.normal));
    EXPECT_TRUE(same(a.position, b.position));
    EXPECT_TRUE(same(a.primId, b.primId));
    EXPECT_TRUE(same(a.geomId, b.geomId));
    EXPECT_FALSE(a.rgba.empty());
  }
}

}  // namespace
}  // namespace aperture
