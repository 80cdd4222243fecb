// The scene-box test (core/engine/scene_box.h, RenderSettings::sceneBoxTest): the frame loop
// resolves rays that miss the scene's box as misses without Embree. Checked three ways: the lane
// test never clears a ray that reaches the box (rays aimed exactly at its faces, edges and corners,
// from near and far) and clears the rays that clearly miss it, both against a slab test of
// its own in double; the Scene's box holds every placed vertex; and every AOV, layer and count
// of the frame loop is bit-identical with the test on and off, for every camera kind and
// packet width, while the test does resolve rays.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <random>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/packet.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/engine/scene_box.h"
#include "core/mesh/mesh.h"
#include "tests/numerics_support.h"
#include "tests/support.h"

namespace aperture {
namespace scene_box_test {

/// Whether the ray o + t·d, t in [t0, t1], meets the closed box [lo, hi]: the slab test in
/// double, written independently of maskLanesMissingBox (an axis the ray runs parallel to is
/// a test of the origin, not an infinite product).
bool reachesBox(glm::dvec3 o, glm::dvec3 d, double t0, double t1, glm::dvec3 lo, glm::dvec3 hi) {
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    const double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  return t0 <= t1;
}

/// 16 rays in SoA arrays, with RayLanes views for maskLanesMissingBox.
struct Lanes16 {
  alignas(64) float ox[16], oy[16], oz[16], dx[16], dy[16], dz[16], tnear[16], tfar[16];
  alignas(64) int valid[16];
  RayLanes view() {
    RayLanes l;
    l.width = 16;
    l.orgX = ox, l.orgY = oy, l.orgZ = oz, l.dirX = dx, l.dirY = dy, l.dirZ = dz;
    l.tnear = tnear, l.tfar = tfar;
    return l;
  }
  void set(int k, const glm::vec3& o, const glm::vec3& d, float t0, float t1) {
    ox[k] = o.x, oy[k] = o.y, oz[k] = o.z, dx[k] = d.x, dy[k] = d.y, dz[k] = d.z;
    tnear[k] = t0, tfar[k] = t1, valid[k] = -1;
  }
};

TEST(SceneBoxLanes, KeepsEveryRayAimedAtTheBoxAndClearsThoseThatClearlyMissIt) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int aimed = 0, clearlyMissing = 0, cleared = 0;
  for (int round = 0; round < 4000; ++round) {
    // A box somewhere (its size and offset vary over orders of magnitude), the unpadded bounds.
    const double size = std::pow(10.0, -2.0 + 4.0 * unit(rng));
    const glm::dvec3 centre = size * 20.0 * glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng));
    const glm::vec3 loF(centre - size * glm::dvec3(unit(rng), 0.5, unit(rng)));
    const glm::vec3 hiF(centre + size * glm::dvec3(unit(rng), unit(rng), 0.5));
    const glm::dvec3 lo(loF), hi(hiF);
    const SceneBox box = *paddedSceneBox(loF, hiF);
    Lanes16 rays;
    std::vector<bool> reaches(16), missesClearly(16);
    for (int k = 0; k < 16; ++k) {
      // An origin near or far (up to 10^7 box sizes, where the rounding of t, not the box's
      // padding, is what the slack must cover), inside the box for some.
      const double reach = size * std::pow(10.0, -1.0 + 8.0 * unit(rng));
      glm::dvec3 o = centre + reach * glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
      glm::dvec3 target;
      if (k < 10) {
        // Aimed at a point of the box's surface: a face, an edge or a corner (coordinates
        // taken at lo or hi, exactly).
        for (int a = 0; a < 3; ++a) target[a] = lo[a] + (hi[a] - lo[a]) * unit(rng);
        for (int a = 0; a < 3; ++a)
          if (a == k % 3 || (k >= 6 && unit(rng) < 0.5))
            target[a] = unit(rng) < 0.5 ? lo[a] : hi[a];
      } else {
        target =
            centre + 3.0 * size * glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
      }
      glm::dvec3 d = glm::normalize(target - o);
      if (k == 9 || k == 15) d = glm::dvec3(0.0, 0.0, target.z > o.z ? 1.0 : -1.0);  // parallel
      const glm::vec3 of(o), df(d);
      // Clip intervals on some lanes: [0, inf) mostly.
      const float t0 = k % 4 == 3 ? float(0.5 * reach) : 0.0f;
      const float t1 = k % 5 == 4 ? float(2.0 * reach) : std::numeric_limits<float>::infinity();
      rays.set(k, of, df, t0, t1);
      const glm::dvec3 od(of), dd(df);
      reaches[size_t(k)] = reachesBox(od, dd, t0, t1, lo, hi);
      // Clearly: it misses the box grown by a hundredth of its size and a ten-thousandth of
      // the origin's distance (the slack is 2^-18 of t), over an interval grown by 1 %.
      const double margin = 1e-2 * size + 1e-4 * glm::length(od - centre);
      missesClearly[size_t(k)] =
          !reachesBox(od, dd, t0 * (1 - 1e-2), t1 * (1 + 1e-2), lo - margin, hi + margin);
    }
    const RayLanes view = rays.view();
    cleared += maskLanesMissingBox<16>(box, view, rays.valid);
    for (int k = 0; k < 16; ++k) {
      if (reaches[size_t(k)]) {
        ++aimed;
        EXPECT_NE(rays.valid[k], 0) << "round " << round << " lane " << k << ": reaches the box";
      }
      if (missesClearly[size_t(k)]) {
        ++clearlyMissing;
        EXPECT_EQ(rays.valid[k], 0) << "round " << round << " lane " << k << ": misses clearly";
      }
    }
  }
  // Both kinds were exercised in numbers, and the count returned is the lanes cleared.
  EXPECT_GT(aimed, 30000);
  EXPECT_GT(clearlyMissing, 3000);
  EXPECT_GE(cleared, clearlyMissing);
}

TEST(SceneBoxLanes, InactiveLanesStayInactiveAndAreNotCounted) {
  Lanes16 rays;
  const SceneBox box = *paddedSceneBox(glm::vec3(-1.0f), glm::vec3(1.0f));
  for (int k = 0; k < 16; ++k) rays.set(k, {0, 0, 5}, {0, 0, k < 8 ? -1.0f : 1.0f}, 0, INFINITY);
  for (int k = 0; k < 16; k += 2) rays.valid[k] = 0;
  const RayLanes view = rays.view();
  // Lanes 8..15 point away: of them, the odd ones were active.
  EXPECT_EQ(maskLanesMissingBox<16>(box, view, rays.valid), 4);
  for (int k = 0; k < 16; ++k) EXPECT_EQ(rays.valid[k], k < 8 && k % 2 == 1 ? -1 : 0) << k;
}

TEST(SceneBoxPadding, HoldsTheBoundsAndRefusesEmptyOrNonFiniteOnes) {
  const glm::vec3 lo(1000.0f, -2.0f, 3.0f), hi(1001.0f, -1.0f, 3.0f);  // flat in z, far in x
  const auto box = paddedSceneBox(lo, hi);
  ASSERT_TRUE(box.has_value());
  for (int a = 0; a < 3; ++a) {
    // Grown by kSceneBoxPadding of the largest magnitude (1001), not more than twice that.
    EXPECT_LE(box->lo[a], lo[a] - kSceneBoxPadding * 1001.0f * 0.99f) << a;
    EXPECT_GE(box->hi[a], hi[a] + kSceneBoxPadding * 1001.0f * 0.99f) << a;
    EXPECT_GT(box->lo[a], lo[a] - 2.0f * kSceneBoxPadding * 1001.0f) << a;
  }
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(paddedSceneBox(glm::vec3(inf), glm::vec3(-inf)).has_value());  // Embree's empty
  EXPECT_FALSE(paddedSceneBox(glm::vec3(0.0f), glm::vec3(1.0f, NAN, 1.0f)).has_value());
  EXPECT_FALSE(paddedSceneBox(glm::vec3(0.0f, 2.0f, 0.0f), glm::vec3(1.0f)).has_value());
}

/// The render-space box of the vertices of `objects`, in double.
void placedBounds(const std::vector<SceneObject>& objects, const glm::dvec3& renderOrigin,
                  glm::dvec3& lo, glm::dvec3& hi) {
  lo = glm::dvec3(INFINITY), hi = glm::dvec3(-INFINITY);
  for (const SceneObject& o : objects)
    for (size_t v = 0; v < o.mesh->vertexCount; ++v) {
      // World = worldFromMesh · (anchor + position), in double; render space is relative to
      // the render origin.
      const glm::dvec3 local = o.mesh->anchor + glm::dvec3(o.mesh->vertex(uint32_t(v)));
      const glm::dvec3 p = glm::dvec3(o.worldFromMesh * glm::dvec4(local, 1.0)) - renderOrigin;
      lo = glm::min(lo, p), hi = glm::max(hi, p);
    }
}

TEST(SceneBoxScene, HoldsEveryPlacedVertexAndIsTightForAMeshAttachedDirectly) {
  const Mesh mesh = loadMesh("procedural:spheres?tris=2000");
  glm::dvec3 lo, hi;
  // Placed twice: the second through an Embree instance, whose bounds Embree takes from the
  // placed box of the mesh, so the box holds the vertices but may be larger.
  const std::vector<SceneObject> objects = test::placedTwice(mesh, {40.0, -5.0, 12.0});
  const Scene instanced(test::numericsDevice(), objects);
  ASSERT_TRUE(instanced.box().has_value());
  placedBounds(objects, instanced.renderOrigin(), lo, hi);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LT(double(instanced.box()->lo[a]), lo[a]) << a;
    EXPECT_GT(double(instanced.box()->hi[a]), hi[a]) << a;
  }
  // Attached directly: the vertices' own box, padded by 2^-14 of its size.
  const Scene direct(test::numericsDevice(), {SceneObject{&mesh}});
  ASSERT_TRUE(direct.box().has_value());
  placedBounds({SceneObject{&mesh}}, direct.renderOrigin(), lo, hi);
  const double size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  for (int a = 0; a < 3; ++a) {
    EXPECT_LT(double(direct.box()->lo[a]), lo[a]) << a;
    EXPECT_GT(double(direct.box()->hi[a]), hi[a]) << a;
    EXPECT_GT(double(direct.box()->lo[a]), lo[a] - 1e-3 * size) << a;
    EXPECT_LT(double(direct.box()->hi[a]), hi[a] + 1e-3 * size) << a;
  }
}

/// Every camera kind, framed so that part of each image is background.
std::vector<CameraParams> cameraKinds() {
  std::vector<CameraParams> all;
  CameraParams p = test::lookAt({30.0, 12.0, 60.0}, {20.0, 0.0, 5.0}, 61, 43);
  all.push_back(p);
  CameraParams clipped = p;  // depth range cutting the scene: tnear and tfar
  clipped.clip = glm::dvec2(55.0, 70.0);
  all.push_back(clipped);
  CameraParams lens = p;
  lens.type = "thinlens";
  lens.apertureRadius = 1.5;
  lens.focusDistance = 60.0;
  lens.spp = 4;
  all.push_back(lens);
  CameraParams ortho = p;  // straight down −z: directions with zero x and y
  ortho.type = "orthographic";
  ortho.eye = {20.0, 0.0, 80.0};
  ortho.at = glm::dvec3(20.0, 0.0, 0.0);
  ortho.viewport = glm::dvec2(90.0, 60.0);
  ortho.fovDeg.reset();
  all.push_back(ortho);
  CameraParams pano = p;  // from outside the scene: most directions miss
  pano.type = "equirect";
  pano.fovDeg.reset();
  all.push_back(pano);
  CameraParams inside = pano;  // from inside the box: nothing to resolve
  inside.eye = {20.0, -2.0, 6.0};
  all.push_back(inside);
  CameraParams fisheye = p;
  fisheye.type = "fisheye";
  fisheye.fovDeg.reset();
  all.push_back(fisheye);
  all.push_back(test::calibratedOpenCvLike(p));
  return all;
}

TEST(SceneBoxCameras, ASharedRayOriginIsWhereEveryGeneratedRayStartsAtTnearZero) {
  const std::vector<CameraParams> kinds = cameraKinds();
  int shared = 0;
  for (const CameraParams& p : kinds) {
    const auto camera = makeCamera(p, glm::dvec3(1.0, 2.0, 3.0));
    const std::optional<glm::vec3> origin = camera->sharedRayOrigin();
    const std::string what = p.type + (p.clip ? " clipped" : "");
    // The models with one centre of projection and no clip say so; the others must not.
    const bool expected = (p.type == "perspective" && !p.clip) || p.type == "equirect" ||
                          p.type == "fisheye" || p.type == "calibrated";
    EXPECT_EQ(origin.has_value(), expected) << what;
    if (!origin) continue;
    ++shared;
    PacketBuffers<16> packet;
    int lanes = 0;
    for (int sample = -1; sample < p.spp; ++sample)
      for (int y0 = 0; y0 < p.height; y0 += 4)
        for (int x0 = 0; x0 < p.width; x0 += 4) {
          const PacketRequest req{x0, y0, 4, 4, sample < 0 ? PacketRequest::kCentreRay : sample};
          camera->generate(req, packet.lanes, packet.valid);
          for (int k = 0; k < 16; ++k) {
            if (!packet.valid[k]) continue;
            ++lanes;
            ASSERT_EQ(packet.lanes.orgX[k], origin->x) << what;
            ASSERT_EQ(packet.lanes.orgY[k], origin->y) << what;
            ASSERT_EQ(packet.lanes.orgZ[k], origin->z) << what;
            ASSERT_EQ(packet.lanes.tnear[k], 0.0f) << what;
          }
        }
    EXPECT_GT(lanes, p.width * p.height / 3) << what;
  }
  EXPECT_EQ(shared, 5);  // perspective, both panoramas seen from two places, calibrated
}

/// Every AOV and two layers of `p`, with the scene-box test on or off.
Framebuffer renderWith(const Scene& scene, const CameraParams& p, bool boxTest, int packet,
                       RenderStats& stats) {
  AovSet aovs = parseAovList("all");
  aovs.layers = 2;
  RenderSettings rs;
  rs.packetWidth = packet;
  rs.tileSize = 8;
  rs.sceneBoxTest = boxTest;
  return test::render(scene, p, aovs, &stats, rs);
}

TEST(SceneBoxFrameLoop, EveryAovLayerAndCountIsBitIdenticalWithTheTestOnAndOff) {
  const Mesh mesh = loadMesh("procedural:spheres?tris=6000");
  const Scene scene(test::numericsDevice(), test::placedTwice(mesh, {40.0, -5.0, 12.0}));
  uint64_t resolved = 0;
  const std::vector<CameraParams> kinds = cameraKinds();
  for (const CameraParams& p : kinds)
    for (int packet : {1, 4, 16}) {
      const std::string what = p.type + " eye z " + std::to_string(p.eye.z) + " packet " +
                               std::to_string(packet) + (p.clip ? " clipped" : "");
      RenderStats on, off;
      const Framebuffer withTest = renderWith(scene, p, true, packet, on);
      const Framebuffer without = renderWith(scene, p, false, packet, off);
      test::expectSameFrameFewerEmbreeRays(withTest, without, on, off, what);
      EXPECT_EQ(off.raysOutsideBox, 0u) << what;
      resolved += on.raysOutsideBox;
      if (p.eye.z == 6.0)
        EXPECT_EQ(on.raysOutsideBox, 0u) << what << ": the eye is in the box";
      else
        EXPECT_GT(on.raysOutsideBox, 0u) << what << ": part of the image is background";
    }
  EXPECT_GT(resolved, 10000u);
}

}  // namespace scene_box_test
}  // namespace aperture
