// Numerics of placement: far-from-origin scenes (camera-relative vs world space) and depth
// precision. Part of the numerics tests (issue 5): each test checks a closed form or an independent
// path; the world-space float32 mode's errors are measured and printed (docs/numerics.md records
// them), not asserted.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
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

// --- Translation invariance ------------------------------------------------------------

// The city and its camera moved by T (in double: LoadOptions.translate and eye/at + T).
// Camera-relative: the mesh is stored relative to its bounding-box centre and the camera's
// origin is computed in double relative to it, so the image must not change. World-space:
// float32 world coordinates; the error grows with T and is printed, not asserted.
TEST(NumericsTranslation, CameraRelativeIsInvariantWorldSpaceErrorIsMeasured) {
  const AovMask aovs = kAovDepth | kAovDistance | kAovPrimId;
  const glm::dvec3 dirT = glm::normalize(glm::dvec3(1.0, 0.5, -0.75));
  auto renderAt = [&](double t, Placement placement) {
    LoadOptions lo;
    lo.placement = placement;
    lo.translate = t * dirT;
    const Loaded l = load("procedural:city", lo);
    CameraParams p =
        lookAt(glm::dvec3(14, 11, 18) + t * dirT, glm::dvec3(0, 1, 0) + t * dirT, 192, 128);
    return render(*l.scene, p, aovs);
  };
  const Framebuffer ref = renderAt(0.0, Placement::CameraRelative);
  std::printf("[ info ] translation T | mode            | primID agree | max rel Z  | max rel T\n");
  for (double t : {1e3, 1e5, 1e6, 1e7}) {
    for (Placement pl : {Placement::CameraRelative, Placement::WorldSpace}) {
      const Agreement g = compare(renderAt(t, pl), ref);
      const bool rel = pl == Placement::CameraRelative;
      std::printf("[ info ] %13.0e | %-15s | %11.4f%% | %10.3e | %10.3e\n", t,
                  rel ? "camera-relative" : "world-space", 100.0 * g.primIdShare, g.maxZ, g.maxT);
      if (rel) {
        EXPECT_GE(g.primIdShare, 0.999) << "T = " << t;
        EXPECT_LE(g.maxZ, 1e-5) << "T = " << t;
        EXPECT_LE(g.maxT, 1e-5) << "T = " << t;
      }
    }
  }
}

// The header and P of a far render: P is reconstructed in double (render origin + org + t·dir)
// and rounded once, so it is as exact as float allows at 1e7.
TEST(NumericsTranslation, PositionAtOneE7IsTheNearestFloatOfTheHitPoint) {
  const double t = 1e7;
  LoadOptions lo;
  lo.translate = glm::dvec3(t, t, t);
  const Loaded l = load("procedural:quad?size=4&z=0", lo);  // plane z = 1e7
  CameraParams p = lookAt(glm::dvec3(t, t, t + 3), glm::dvec3(t, t, t), 32, 32);
  const Framebuffer fb = render(*l.scene, p, kAovPosition | kAovDepth);
  for (size_t i = 0; i < fb.pixelCount(); ++i) {
    ASSERT_EQ(fb.position[3 * i + 2], float(t)) << i;
    EXPECT_NEAR(fb.depth[i], 3.0, 3.0 * 1e-6);
  }
}

// --- Depth precision -------------------------------------------------------------------

TEST(NumericsDepth, PlanesFrom1e2To1e6GiveZAndTWithin1e6StoredAsFloat32) {
  const std::string dir = test::scratchDir();
  for (double D : {1e-2, 1.0, 1e2, 1e4, 1e6}) {
    // A plane at depth D, wide enough for a 40° field.
    const Loaded l =
        load("procedural:quad?size=" + std::to_string(4 * D) + "&z=" + std::to_string(-D));
    CameraParams p;
    p.eye = glm::dvec3(0.0);
    p.dir = glm::dvec3(0, 0, -1);
    p.width = 24;
    p.height = 16;
    p.fovDeg = 40;
    const Framebuffer fb = render(*l.scene, p, kAovColor | kAovDepth | kAovDistance);
    const auto cam = makeCameraModel(p, l.scene->renderOrigin());
    double maxZ = 0, maxT = 0;
    for (int i = 0; i < p.height; ++i)
      for (int j = 0; j < p.width; ++j) {
        const size_t px = size_t(i) * size_t(p.width) + size_t(j);
        glm::dvec3 org, d;
        cam->ray(j + 0.5, i + 0.5, 0.5, 0.5, org, d);
        const glm::dvec3 df = glm::dvec3(glm::vec3(d));  // the float direction traced
        maxZ = std::max(maxZ, relErr(fb.depth[px], D));
        maxT = std::max(maxT, relErr(fb.distance[px], D / -df.z));
      }
    EXPECT_LE(maxZ, 1e-6) << "D = " << D;
    EXPECT_LE(maxT, 1e-6) << "D = " << D;
    std::printf("[ info ] plane at %g: max rel error Z %.2e, T %.2e\n", D, maxZ, maxT);

    // Stored float32 even with half color, and read back exactly.
    const std::string path = dir + "/d.exr";
    ExrMetadata meta;
    meta.camera = cam->describe();
    ExrOptions opt;
    opt.halfColor = true;
    writeExr(path, fb, meta, opt);
    Imf::InputFile file(path.c_str());
    const Imf::ChannelList& ch = file.header().channels();
    ASSERT_NE(ch.findChannel("Z"), nullptr);
    ASSERT_NE(ch.findChannel("T"), nullptr);
    EXPECT_EQ(ch.findChannel("Z")->type, Imf::FLOAT);
    EXPECT_EQ(ch.findChannel("T")->type, Imf::FLOAT);
    EXPECT_EQ(ch.findChannel("R")->type, Imf::HALF);
    const Framebuffer back = readExr(path);
    EXPECT_EQ(0, std::memcmp(back.depth.data(), fb.depth.data(), fb.depth.size() * 4));
    EXPECT_EQ(0, std::memcmp(back.distance.data(), fb.distance.data(), fb.distance.size() * 4));
  }
}

}  // namespace
}  // namespace aperture
