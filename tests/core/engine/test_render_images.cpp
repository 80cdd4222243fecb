// renderImages (several frames in one parallel loop over (camera, tile)) against renderImage
// of each frame alone: the independent path is the one-frame loop every other test checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// A sphere in front of a quad: two objects, so geomID varies across the image.
struct TwoObjects {
  Device device;
  Mesh sphere = makeProcedural("procedural:sphere");
  Mesh plane = makeProcedural("procedural:quad?size=8&z=-1.5");
  std::unique_ptr<Scene> scene;
  TwoObjects() {
    LoadOptions o;
    o.placement = Placement::WorldSpace;
    finishMesh(sphere, o);
    finishMesh(plane, o);
    scene = std::make_unique<Scene>(device, std::vector<const Mesh*>{&sphere, &plane});
  }
};

CameraParams cameraOf(const char* type, int width, int height, int spp) {
  CameraParams p;
  p.type = type;
  p.width = width;
  p.height = height;
  p.spp = spp;
  p.eye = {0.3, 1.5, 4.0};
  p.at = glm::dvec3(0.0, 0.0, 0.0);
  if (p.type == "orthographic") p.viewport = glm::dvec2(4.0, 3.0);
  return p;
}

const AovSet kEveryFixedAov = parseAovSet("all");

/// The cameras of `params` placed for the scene's render origin, and their pointers in order.
struct CamerasOf {
  CamerasOf(const std::vector<CameraParams>& params, const glm::dvec3& renderOrigin) {
    for (const CameraParams& p : params) {
      owned.push_back(makeCamera(p, renderOrigin));
      cameras.push_back(owned.back().get());
    }
  }
  std::vector<std::unique_ptr<Camera>> owned;
  std::vector<const Camera*> cameras;
};

}  // namespace

TEST(RenderImages, EachFrameEqualsRenderImageForMixedSizesAndTypes) {
  TwoObjects s;
  // Sizes that are not multiples of the tile or block size, one frame smaller than a tile,
  // several camera models and spp (colour averages samples; geometry from the centre ray).
  const std::vector<CameraParams> params = {
      cameraOf("perspective", 97, 61, 1), cameraOf("orthographic", 33, 70, 1),
      cameraOf("thinlens", 40, 40, 4),    cameraOf("equirect", 128, 64, 1),
      cameraOf("fisheye", 17, 5, 2),      cameraOf("perspective", 1, 1, 1),
  };
  std::vector<std::unique_ptr<Camera>> owned;
  std::vector<const Camera*> cameras;
  std::vector<Framebuffer> batch;
  for (const CameraParams& p : params) {
    owned.push_back(makeCamera(p, s.scene->renderOrigin()));
    cameras.push_back(owned.back().get());
    batch.emplace_back(p.width, p.height, kEveryFixedAov);
  }
  RenderSettings settings;
  settings.tileSize = 16;
  const std::vector<RenderStats> stats = renderImages(*s.scene, cameras, settings, batch);
  ASSERT_EQ(stats.size(), params.size());
  uint64_t anyHits = 0;
  for (size_t k = 0; k < params.size(); ++k) {
    Framebuffer alone(params[k].width, params[k].height, kEveryFixedAov);
    RenderSettings one = settings;
    one.spp = params[k].spp;
    const RenderStats single = renderImage(*s.scene, *cameras[k], one, alone);
    EXPECT_EQ(test::differingAovs(batch[k], alone), "") << "frame " << k << " " << params[k].type;
    EXPECT_EQ(stats[k].raysTraced, single.raysTraced) << "frame " << k;
    EXPECT_EQ(stats[k].hits, single.hits) << "frame " << k;
    EXPECT_EQ(stats[k].raysSkipped, single.raysSkipped) << "frame " << k;
    anyHits += single.hits;
  }
  EXPECT_GT(anyHits, 1000u) << "the cameras should see the scene";
}

TEST(RenderImages, ProgressCountsEveryFrameOnceInOrder) {
  TwoObjects s;
  std::vector<std::unique_ptr<Camera>> owned;
  std::vector<const Camera*> cameras;
  std::vector<Framebuffer> fbs;
  for (int k = 0; k < 7; ++k) {
    owned.push_back(makeCamera(cameraOf("perspective", 20 + 9 * k, 30, 1)));
    cameras.push_back(owned.back().get());
    fbs.emplace_back(20 + 9 * k, 30, AovSet(kAovDepth));
  }
  std::vector<size_t> calls;
  renderImages(*s.scene, cameras, RenderSettings{}, fbs,
               [&](size_t done) { calls.push_back(done); });
  const std::vector<size_t> expected = {1, 2, 3, 4, 5, 6, 7};
  EXPECT_EQ(calls, expected);
}

TEST(RenderImages, RefusesMismatchedFramebuffers) {
  TwoObjects s;
  const auto camera = makeCamera(cameraOf("perspective", 32, 32, 1));
  std::vector<const Camera*> cameras = {camera.get(), camera.get()};
  std::vector<Framebuffer> one = {Framebuffer(32, 32, AovSet(kAovDepth))};
  EXPECT_THROW(renderImages(*s.scene, cameras, RenderSettings{}, one), Error);
  std::vector<Framebuffer> wrongSize = {Framebuffer(32, 32, AovSet(kAovDepth)),
                                        Framebuffer(31, 32, AovSet(kAovDepth))};
  EXPECT_THROW(renderImages(*s.scene, cameras, RenderSettings{}, wrongSize), Error);
}

namespace {

/// Frame k of a stacked framebuffer: its rows [k·H, (k+1)·H) as a framebuffer of its own,
/// layers included (layer-major over the stacked image).
Framebuffer frameOfStack(const Framebuffer& stacked, size_t k, int height) {
  Framebuffer f(stacked.width, height, stacked.aovSet());
  const size_t n = f.pixelCount(), at = k * n, all = stacked.pixelCount();
  auto slice = [&](const auto& from, auto& to, size_t per) {
    if (!from.empty()) std::copy_n(from.begin() + std::ptrdiff_t(at * per), n * per, to.begin());
  };
  slice(stacked.rgba, f.rgba, 4);
  slice(stacked.depth, f.depth, 1);
  slice(stacked.distance, f.distance, 1);
  slice(stacked.normal, f.normal, 3);
  slice(stacked.position, f.position, 3);
  slice(stacked.primId, f.primId, 1);
  slice(stacked.geomId, f.geomId, 1);
  slice(stacked.shadingNormal, f.shadingNormal, 3);
  for (size_t c = 0; c < stacked.properties.size(); ++c)
    slice(stacked.properties[c].values, f.properties[c].values, 1);
  auto sliceLayers = [&](const auto& from, auto& to) {
    for (int layer = 0; layer < stacked.layers; ++layer)
      std::copy_n(from.begin() + std::ptrdiff_t(size_t(layer) * all + at), n,
                  to.begin() + std::ptrdiff_t(size_t(layer) * n));
  };
  sliceLayers(stacked.layerDepth, f.layerDepth);
  sliceLayers(stacked.layerDistance, f.layerDistance);
  sliceLayers(stacked.layerPrimId, f.layerPrimId);
  sliceLayers(stacked.layerGeomId, f.layerGeomId);
  return f;
}

}  // namespace

TEST(RenderImages, StackedFramesEqualRenderImageOfEach) {
  TwoObjects s;
  // One size (not a multiple of the tile or block), several models and spp; colour, every
  // geometry AOV and two layers, so a wrong pixel offset in any store shows up.
  const int w = 45, h = 29;
  const std::vector<CameraParams> params = {
      cameraOf("perspective", w, h, 1), cameraOf("thinlens", w, h, 4),
      cameraOf("orthographic", w, h, 1), cameraOf("fisheye", w, h, 1)};
  const CamerasOf placed(params, s.scene->renderOrigin());
  const std::vector<const Camera*>& cameras = placed.cameras;
  AovSet aovs = kEveryFixedAov;
  aovs.layers = 2;
  Framebuffer stacked(w, h * int(params.size()), aovs);
  RenderSettings settings;
  settings.tileSize = 16;
  const std::vector<RenderStats> stats = renderImagesStacked(*s.scene, cameras, settings, stacked);
  ASSERT_EQ(stats.size(), params.size());
  for (size_t k = 0; k < params.size(); ++k) {
    Framebuffer alone(w, h, aovs);
    RenderSettings one = settings;
    one.spp = params[k].spp;
    const RenderStats single = renderImage(*s.scene, *cameras[k], one, alone);
    EXPECT_GT(single.hits, 100u) << "frame " << k << " should see the scene";
    const Framebuffer frame = frameOfStack(stacked, k, h);
    EXPECT_EQ(test::differingAovs(frame, alone), "") << "frame " << k << " " << params[k].type;
    EXPECT_EQ(stats[k].raysTraced, single.raysTraced) << "frame " << k;
  }
}

TEST(RenderImages, StackedRefusesMixedSizesAndAWrongHeight) {
  TwoObjects s;
  const auto a = makeCamera(cameraOf("perspective", 32, 20, 1));
  const auto b = makeCamera(cameraOf("perspective", 32, 21, 1));
  Framebuffer twoFrames(32, 40, AovSet(kAovDepth));
  EXPECT_THROW(renderImagesStacked(*s.scene, {a.get(), b.get()}, RenderSettings{}, twoFrames),
               Error);
  Framebuffer wrongHeight(32, 41, AovSet(kAovDepth));
  EXPECT_THROW(renderImagesStacked(*s.scene, {a.get(), a.get()}, RenderSettings{}, wrongHeight),
               Error);
}

namespace {

/// Storage for every channel of `px`, each value set to the bits `pattern`, bound to `px`: what
/// the render leaves unwritten keeps the pattern.
std::vector<std::vector<uint32_t>> bindFilledStorage(FramePixels& px, uint32_t pattern) {
  std::vector<std::vector<uint32_t>> storage;
  for (PixelChannel& c : px.channels) {
    storage.emplace_back(c.valueCount(px.pixelCount()), pattern);
    c.data = storage.back().data();
  }
  return storage;
}

/// The AOVs of `px` that differ, bit for bit, from those of `fb` ("" when none).
std::string differingChannels(const FramePixels& px, const Framebuffer& fb) {
  std::string out;
  for (const PixelChannel& c : px.channels) {
    const ImageView v = aovView(fb, c.name);
    const void* theirs = v.f32 ? static_cast<const void*>(v.f32) : v.u32;
    if (std::memcmp(c.data, theirs, sizeof(uint32_t) * c.valueCount(px.pixelCount())) != 0)
      out += c.name + " ";
  }
  return out;
}

}  // namespace

TEST(RenderImages, StorageNothingWroteGetsEveryValueOfAFramebuffer) {
  TwoObjects s;
  // Every fixed AOV, two layers (most pixels have fewer surfaces: missing layers), misses at the
  // image's edges, sizes that cut tiles and blocks, spp 4 colour.
  const int w = 45, h = 29;
  const std::vector<CameraParams> params = {cameraOf("perspective", w, h, 1),
                                            cameraOf("thinlens", w, h, 4),
                                            cameraOf("orthographic", w, h, 1)};
  const CamerasOf placed(params, s.scene->renderOrigin());
  const std::vector<const Camera*>& cameras = placed.cameras;
  AovSet aovs = kEveryFixedAov;
  aovs.layers = 2;
  RenderSettings settings;
  settings.tileSize = 16;
  Framebuffer stacked(w, h * int(params.size()), aovs);
  renderImagesStacked(*s.scene, cameras, settings, stacked);
  ASSERT_TRUE(std::any_of(stacked.depth.begin(), stacked.depth.end(), [](float z) {
    return std::isinf(z);
  })) << "the frames should have misses";
  for (const uint32_t pattern : {0xFFFFFFFFu, 0x7FC00001u, 0u, 0x12345678u}) {
    FramePixels px = unboundPixels(w, h * int(params.size()), aovs);
    ASSERT_FALSE(px.missesWritten);
    const auto storage = bindFilledStorage(px, pattern);
    renderImagesStacked(*s.scene, cameras, settings, px);
    EXPECT_EQ(differingChannels(px, stacked), "") << "storage filled with " << pattern;
  }
  // One frame at a time (renderImages over FramePixels) as well.
  std::vector<FramePixels> frames;
  std::vector<std::vector<std::vector<uint32_t>>> storage;
  for (size_t k = 0; k < params.size(); ++k) {
    frames.push_back(unboundPixels(w, h, aovs));
    storage.push_back(bindFilledStorage(frames.back(), 0x7FC00001u));
  }
  renderImages(*s.scene, cameras, settings, frames);
  for (size_t k = 0; k < params.size(); ++k)
    EXPECT_EQ(differingChannels(frames[k], frameOfStack(stacked, k, h)), "") << "frame " << k;
}

TEST(RenderImages, StorageWithoutAChannelIsRefused) {
  TwoObjects s;
  const auto camera = makeCamera(cameraOf("perspective", 32, 20, 1));
  FramePixels px = unboundPixels(32, 20, parseAovSet("depth,normal"));
  std::vector<float> depth(px.pixelCount());
  px.channels[0].data = depth.data();  // normal has none
  EXPECT_THROW(renderImagesStacked(*s.scene, {camera.get()}, RenderSettings{}, px), Error);
  EXPECT_THROW(renderImages(*s.scene, {camera.get()}, RenderSettings{}, {px}), Error);
}

TEST(RenderImages, EveryPathRefusesTheSameBadStorageNamingIt) {
  TwoObjects s;
  const auto camera = makeCamera(cameraOf("perspective", 32, 20, 1));
  const std::vector<const Camera*> one = {camera.get()};
  // Storage with no AOV, then one row short of the camera's 32x20: each path says which call
  // refused it and the storage's size.
  for (const auto& [fb, sizeText] :
       {std::pair<Framebuffer, std::string>{Framebuffer(32, 20, AovSet()), "32x20 with AOVs ''"},
        {Framebuffer(32, 19, AovSet(kAovDepth)), "32x19 does not"}}) {
    Framebuffer single = fb, stacked = fb;
    std::vector<Framebuffer> frames = {fb};
    const std::string a = test::errorOf([&] { renderImage(*s.scene, *camera, {}, single); });
    const std::string b = test::errorOf([&] { renderImages(*s.scene, one, {}, frames); });
    const std::string c = test::errorOf([&] { renderImagesStacked(*s.scene, one, {}, stacked); });
    EXPECT_NE(a.find("renderImage: framebuffer " + sizeText), std::string::npos) << a;
    EXPECT_NE(b.find("renderImages: frame 0: framebuffer " + sizeText), std::string::npos) << b;
    EXPECT_NE(c.find("renderImagesStacked: framebuffer " + sizeText), std::string::npos) << c;
  }
  Framebuffer fb(32, 20, AovSet(kAovDepth));
  RenderSettings fourSpp;
  fourSpp.spp = 4;
  const std::string spp = test::errorOf([&] { renderImage(*s.scene, *camera, fourSpp, fb); });
  EXPECT_NE(spp.find("the camera's spp 1 does not match the settings' spp 4"), std::string::npos)
      << spp;
  EXPECT_EQ(test::errorOf([&] { renderImagesStacked(*s.scene, {}, {}, fb); }),
            "renderImagesStacked: no camera");
}
