// The camera attributes of the EXR header, as OpenEXR's standard attributes define them
// (website/StandardAttributes.rst, ImfStandardAttributes.h): images rendered by the `aperture`
// binary, read back through OpenEXR's own API, and every hit pixel's P channel projected
// through the header:
//  - worldToCamera: camera space is left-handed, +x right, +y up, +z the viewing direction
//    (points in front have z > 0, and z is the planar depth Z);
//  - worldToNDC: (0, 0) is the top-left and (1, 1) the bottom-right corner of the display
//    window, so NDC · (W, H) is the pixel centre (j + ½, i + ½);
//  - pixelAspectRatio: width over height of a pixel; screen window: the image's rectangle on
//    the plane z = 1 (perspective);
//  - panoramas: no worldToNDC; their aperture.equirect.* / aperture.fisheye.* attributes with
//    the README's formulas give each pixel's direction.
// The wrong conventions (the old −z camera space, a bottom-left NDC origin) are computed too and
// must fail the same checks.
#include <Imath/ImathMatrix.h>
#include <Imath/ImathVec.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfMatrixAttribute.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfVecAttribute.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "core/exr/exr.h"
#include "core/util/units.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::kMaxPixelError;
constexpr double kMaxDepthError = 1e-4;  // relative

/// An image rendered by the binary: its pixels (P, Z, T) and its header as OpenEXR reads it.
struct Rendered {
  Framebuffer fb;
  Imf::Header header;
};

Rendered render(const std::string& name, const std::string& flags) {
  const std::string exr = test::scratchDir() + "/" + name + ".exr";
  std::string out;
  const int code = test::runCommand(test::apertureBinary() +
                                        " render --quiet --aov position,depth,distance --out " +
                                        exr + " " + flags,
                                    &out);
  EXPECT_EQ(code, 0) << flags << "\n" << out;
  if (code != 0) return {};
  Imf::InputFile file(exr.c_str());
  return {readExr(exr), file.header()};
}

/// p · M with the homogeneous divide (Imath's row-vector convention).
Imath::V3d apply(const Imath::M44d& m, const Imath::V3d& p) {
  Imath::V3d q;
  m.multVecMatrix(p, q);
  return q;
}

Imath::V3d headerVector(const Imf::Header& h, const char* name) {
  const auto* a = h.findTypedAttribute<Imf::V3dAttribute>(name);
  EXPECT_NE(a, nullptr) << name;
  return a ? a->value() : Imath::V3d(0.0);
}

/// The camera space of the old headers, built from the frame attributes: rows U, V, W (the
/// OpenGL convention: the view direction is −z, points in front have z < 0).
Imath::M44d oldCameraFromWorld(const Imf::Header& h) {
  const Imath::V3d e = headerVector(h, "aperture.camera.eye");
  const Imath::V3d axes[3] = {headerVector(h, "aperture.camera.U"),
                              headerVector(h, "aperture.camera.V"),
                              headerVector(h, "aperture.camera.W")};
  Imath::M44d m;  // identity; row-vector layout: column c holds axis c
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < 3; ++k) m[k][c] = axes[c][k];
    m[3][c] = -axes[c].dot(e);
  }
  return m;
}

/// worldToNDC followed by y → 1 − y: NDC with the origin at the bottom-left corner.
Imath::M44d bottomLeftNdc(const Imath::M44d& worldToNdc) {
  Imath::M44d flip;  // (x, y, z, w) → (x, w − y, z, w)
  flip[1][1] = -1.0;
  flip[3][1] = 1.0;
  return worldToNdc * flip;
}

/// How many hit pixels pass each check of a planar camera's matrices.
struct Counts {
  int hits = 0;
  int depth = 0;  ///< camera z > 0 and equal to Z within kMaxDepthError relative
  int pixel = 0;  ///< NDC · (W, H) on the pixel centre within kMaxPixelError
};

Counts countMatches(const Framebuffer& fb, const Imath::M44d& worldToCamera,
                    const Imath::M44d& worldToNdc) {
  Counts n;
  n.hits = test::forEachHit(fb, [&](int i, int j, const Imath::V3d& p, double z, double) {
    const Imath::V3d c = apply(worldToCamera, p);
    n.depth += c.z > 0 && std::abs(c.z - z) <= kMaxDepthError * z;
    const Imath::V3d ndc = apply(worldToNdc, p);
    n.pixel += std::abs(ndc.x * fb.width - (j + 0.5)) <= kMaxPixelError &&
               std::abs(ndc.y * fb.height - (i + 0.5)) <= kMaxPixelError;
  });
  return n;
}

/// The float standard matrices, the double copies (which must agree with them) and the checks:
/// every hit pixel passes with the header's matrices, none with the old −z camera space or a
/// bottom-left NDC origin (the test images have an even height, so no row is its own mirror).
void expectStandardMatrices(const Rendered& r) {
  const Imf::Header& h = r.header;
  ASSERT_TRUE(Imf::hasWorldToCamera(h));
  ASSERT_TRUE(Imf::hasWorldToNDC(h));
  const Imath::M44d worldToCamera(Imf::worldToCamera(h)), worldToNdc(Imf::worldToNDC(h));
  const auto* cameraD = h.findTypedAttribute<Imf::M44dAttribute>("aperture.worldToCamera");
  const auto* ndcD = h.findTypedAttribute<Imf::M44dAttribute>("aperture.worldToNDC");
  ASSERT_NE(cameraD, nullptr);
  ASSERT_NE(ndcD, nullptr);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      EXPECT_EQ(float(cameraD->value()[i][j]), worldToCamera[i][j]) << i << "," << j;
      EXPECT_EQ(float(ndcD->value()[i][j]), worldToNdc[i][j]) << i << "," << j;
    }
  // A left-handed camera space from a right-handed world: the rotation part has det −1.
  EXPECT_NEAR(worldToCamera.determinant(), -1.0, 1e-6);

  const Counts got = countMatches(r.fb, worldToCamera, worldToNdc);
  EXPECT_GT(got.hits, r.fb.width * r.fb.height / 5);
  EXPECT_EQ(got.depth, got.hits);
  EXPECT_EQ(got.pixel, got.hits);
  const Counts doubles = countMatches(r.fb, cameraD->value(), ndcD->value());
  EXPECT_EQ(doubles.depth, got.hits);
  EXPECT_EQ(doubles.pixel, got.hits);
  ASSERT_EQ(r.fb.height % 2, 0);
  const Counts old = countMatches(r.fb, oldCameraFromWorld(h), bottomLeftNdc(worldToNdc));
  EXPECT_EQ(old.depth, 0) << "the −z camera space must fail the depth check";
  EXPECT_EQ(old.pixel, 0) << "a bottom-left NDC origin must fail the pixel check";
}

/// Perspective: camera-space (x / z, y / z) of every hit lies on its pixel centre of the
/// screen window (centre C, width Ws, height Ws·H / (W·pixelAspectRatio), x right, y up, on the
/// plane z = 1), i.e. the screen window, the pixel aspect ratio and camera space agree.
void expectScreenWindowHoldsThePixels(const Rendered& r) {
  const Imf::Header& h = r.header;
  const Imath::M44d worldToCamera(Imf::worldToCamera(h));
  const double ws = h.screenWindowWidth(), cx = h.screenWindowCenter().x,
               cy = h.screenWindowCenter().y;
  const double hs = ws * r.fb.height / (r.fb.width * double(h.pixelAspectRatio()));
  const double sxPerPx = ws / r.fb.width, syPerPx = hs / r.fb.height;
  int ok = 0;
  const int hits = test::forEachHit(r.fb, [&](int i, int j, const Imath::V3d& p, double, double) {
    const Imath::V3d c = apply(worldToCamera, p);
    const double sx = cx - 0.5 * ws + (j + 0.5) * sxPerPx;
    const double sy = cy + 0.5 * hs - (i + 0.5) * syPerPx;
    ok += std::abs(c.x / c.z - sx) <= kMaxPixelError * sxPerPx &&
          std::abs(c.y / c.z - sy) <= kMaxPixelError * syPerPx;
  });
  EXPECT_EQ(ok, hits);
}

/// A planar camera rendered from command-line flags, with the closed forms the header must
/// match (from the flags, not from the renderer).
struct PlanarCase {
  const char* name;
  std::string flags;
  int width, height;
  double pixelAspectRatio;  ///< (vw / W) / (vh / H)
  /// Perspective: screen window (centre, width) on the plane z = 1.
  double screenX, screenY, screenWidth;
};

double tanDeg(double deg) { return std::tan(deg * kPi / 180.0); }

const char* const kView = " --eye 6,5,9 --at 0,0.5,0";

std::vector<PlanarCase> perspectiveCases() {
  const double t20 = tanDeg(20.0);  // --fov 40 (vertical): vh / d = 2·tan 20°
  return {
      {"perspective", std::string(kView) + " --fov 40 --size 160,90", 160, 90, 1.0, 0.0, 0.0,
       2 * t20 * 160 / 90},
      {"shifted", std::string(kView) + " --fov 40 --shift 0.2,-0.15 --size 160,90", 160, 90, 1.0,
       0.2 * 2 * t20 * 160 / 90, -0.15 * 2 * t20, 2 * t20 * 160 / 90},
      // Non-square pixels: the viewport's aspect (2.4 / 1.8) is not the image's (160 / 90).
      {"nonsquare", std::string(kView) + " --d 2 --viewport 2.4,1.8 --size 160,90", 160, 90,
       (2.4 / 160) / (1.8 / 90), 0.0, 0.0, 1.2},
  };
}

TEST(ExrHeaders, PerspectiveMatricesProjectPOntoZAndThePixelCentres) {
  for (const PlanarCase& c : perspectiveCases()) {
    SCOPED_TRACE(c.name);
    const Rendered r = render(c.name, c.flags);
    ASSERT_EQ(r.fb.width, c.width);
    ASSERT_EQ(r.fb.height, c.height);
    expectStandardMatrices(r);
    EXPECT_NEAR(r.header.pixelAspectRatio(), c.pixelAspectRatio, 1e-6 * c.pixelAspectRatio);
    EXPECT_NEAR(r.header.screenWindowWidth(), c.screenWidth, 1e-6 * c.screenWidth);
    EXPECT_NEAR(r.header.screenWindowCenter().x, c.screenX, 1e-6);
    EXPECT_NEAR(r.header.screenWindowCenter().y, c.screenY, 1e-6);
    expectScreenWindowHoldsThePixels(r);
  }
}

TEST(ExrHeaders, ArchitecturalTiltIsAShiftOfTheScreenWindow) {
  // Looking down 30°: the view turns horizontal and the tilt becomes the shift d·tan 30° / vh.
  const Rendered r = render("architectural",
                            " --eye 0,6,9 --dir 0,-0.57735026918962576,-1 --fov 50 --architectural"
                            " --size 120,100");
  expectStandardMatrices(r);
  EXPECT_NEAR(r.header.screenWindowCenter().x, 0.0, 1e-6);
  EXPECT_NEAR(r.header.screenWindowCenter().y, -tanDeg(30.0), 1e-6);
  EXPECT_NEAR(r.header.pixelAspectRatio(), 1.0, 1e-6);
  expectScreenWindowHoldsThePixels(r);
}

/// Parallel cameras: camera-space (x − z·tan AX, y − z·tan AY) is the pixel centre's point of
/// the viewport (x right, y up), and the screen window keeps OpenEXR's defaults.
void expectParallelCameraSpace(const Rendered& r, double vw, double vh, double tanX, double tanY) {
  const Imath::M44d worldToCamera(Imf::worldToCamera(r.header));
  const double uPerPx = vw / r.fb.width, vPerPx = vh / r.fb.height;
  int ok = 0;
  const int hits = test::forEachHit(r.fb, [&](int i, int j, const Imath::V3d& p, double, double) {
    const Imath::V3d c = apply(worldToCamera, p);
    const double u = -0.5 * vw + (j + 0.5) * uPerPx, v = 0.5 * vh - (i + 0.5) * vPerPx;
    ok += std::abs(c.x - c.z * tanX - u) <= kMaxPixelError * uPerPx &&
          std::abs(c.y - c.z * tanY - v) <= kMaxPixelError * vPerPx;
  });
  EXPECT_EQ(ok, hits);
  EXPECT_EQ(r.header.screenWindowWidth(), 1.0f);
  EXPECT_EQ(r.header.screenWindowCenter(), Imath::V2f(0, 0));
}

TEST(ExrHeaders, OrthographicAndObliqueMatricesProjectPOntoZAndThePixelCentres) {
  {
    SCOPED_TRACE("orthographic");
    const Rendered r = render(
        "ortho", std::string(kView) + " --camera orthographic --viewport 14,9 --size 150,80");
    expectStandardMatrices(r);
    EXPECT_NEAR(r.header.pixelAspectRatio(), (14.0 / 150) / (9.0 / 80), 1e-6);
    expectParallelCameraSpace(r, 14, 9, 0, 0);
  }
  {
    SCOPED_TRACE("oblique");
    const Rendered r = render("oblique", std::string(kView) +
                                             " --camera oblique --oblique-angles 15,-10"
                                             " --viewport 14,9 --size 140,100");
    expectStandardMatrices(r);
    EXPECT_NEAR(r.header.pixelAspectRatio(), (14.0 / 140) / (9.0 / 100), 1e-6);
    expectParallelCameraSpace(r, 14, 9, tanDeg(15), tanDeg(-10));
  }
}

TEST(ExrHeaders, BunnyPositionsReprojectToTheirPixels) {
  APERTURE_REQUIRE_SHARED_MESH(bunny, "stanford/bun_zipper.ply");
  const Rendered r =
      render("bunny", "--mesh " + bunny +
                          " --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --up 0,1,0 --fov 30"
                          " --size 120,90");
  expectStandardMatrices(r);
  expectScreenWindowHoldsThePixels(r);
}

/// The panorama's raster position of camera-space point c by the README's formulas, from the
/// header's aperture.* attributes; false where the formulas give none.
using PanoramaProjection = std::function<bool(const Imath::V3d& c, double& x, double& y)>;

PanoramaProjection equirectFromHeader(const Imf::Header& h, int width, int height) {
  const auto* lon = h.findTypedAttribute<Imf::V2dAttribute>("aperture.equirect.longitudeRange");
  const auto* lat = h.findTypedAttribute<Imf::V2dAttribute>("aperture.equirect.latitudeRange");
  EXPECT_NE(lon, nullptr);
  EXPECT_NE(lat, nullptr);
  if (!lon || !lat) return {};
  const double lon0 = lon->value().x, lon1 = lon->value().y;
  const double lat0 = lat->value().x, lat1 = lat->value().y;
  return [=](const Imath::V3d& c, double& x, double& y) {
    // direction = (cos lat·sin lon, sin lat, cos lat·cos lon)
    double lonDeg = std::atan2(c.x, c.z) * 180 / kPi;
    const double latDeg = std::atan2(c.y, std::hypot(c.x, c.z)) * 180 / kPi;
    if (lonDeg < lon0) lonDeg += 360;
    x = (lonDeg - lon0) / (lon1 - lon0) * width;
    y = (lat1 - latDeg) / (lat1 - lat0) * height;
    return true;
  };
}

PanoramaProjection fisheyeFromHeader(const Imf::Header& h) {
  const auto* mapping = h.findTypedAttribute<Imf::StringAttribute>("aperture.fisheye.mapping");
  const auto* fov = h.findTypedAttribute<Imf::DoubleAttribute>("aperture.fisheye.fov");
  const auto* centre = h.findTypedAttribute<Imf::V2dAttribute>("aperture.fisheye.center");
  const auto* radius = h.findTypedAttribute<Imf::DoubleAttribute>("aperture.fisheye.radius");
  if (!mapping || !fov || !centre || !radius) {
    ADD_FAILURE() << "missing aperture.fisheye.* attributes";
    return {};
  }
  EXPECT_EQ(mapping->value(), "equidistant");
  const double halfFov = 0.5 * fov->value() * kPi / 180, r = radius->value();
  const Imath::V2d o = centre->value();
  return [=](const Imath::V3d& c, double& x, double& y) {
    // θ = ρ·F / 2 from +z; (a, b) = ρ·(x, y) / |(x, y)|; raster = (cx + R·a, cy − R·b)
    const double lateral = std::hypot(c.x, c.y);
    if (lateral == 0) return false;
    const double rho = std::atan2(lateral, c.z) / halfFov;
    x = o.x + r * rho * c.x / lateral;
    y = o.y - r * rho * c.y / lateral;
    return true;
  };
}

/// Hit pixels whose P, taken to camera space by `worldToCamera` and through `project`, lands
/// on the pixel centre (and whose camera z is Z, within kMaxDepthError of the distance T).
int countPanoramaMatches(const Rendered& r, const Imath::M44d& worldToCamera,
                         const PanoramaProjection& project) {
  int ok = 0;
  test::forEachHit(r.fb, [&](int i, int j, const Imath::V3d& p, double z, double t) {
    const Imath::V3d c = apply(worldToCamera, p);
    double x, y;
    ok += project(c, x, y) && std::abs(x - (j + 0.5)) <= kMaxPixelError &&
          std::abs(y - (i + 0.5)) <= kMaxPixelError && std::abs(c.z - z) <= kMaxDepthError * t;
  });
  return ok;
}

void expectPanorama(const Rendered& r, const PanoramaProjection& project, double pixelAspect) {
  ASSERT_TRUE(project);
  const Imf::Header& h = r.header;
  EXPECT_FALSE(Imf::hasWorldToNDC(h));
  EXPECT_EQ(h.findTypedAttribute<Imf::M44dAttribute>("aperture.worldToNDC"), nullptr);
  ASSERT_TRUE(Imf::hasWorldToCamera(h));
  EXPECT_NEAR(h.pixelAspectRatio(), pixelAspect, 1e-6 * pixelAspect);
  const Imath::M44d worldToCamera(Imf::worldToCamera(h));
  const int hits = test::forEachHit(r.fb, [](int, int, const Imath::V3d&, double, double) {});
  EXPECT_GT(hits, r.fb.width * r.fb.height / 10);
  EXPECT_EQ(countPanoramaMatches(r, worldToCamera, project), hits);
  // The old −z camera space mirrors every direction front to back.
  EXPECT_LT(countPanoramaMatches(r, oldCameraFromWorld(h), project), hits / 50);
}

TEST(ExrHeaders, PanoramasHaveNoWorldToNdcAndTheirAttributesGiveEachPixelsDirection) {
  {
    SCOPED_TRACE("equirect");
    const Rendered r = render("equirect",
                              " --camera equirect --eye 1,4,7 --dir 0,-0.3,-1 --lon -150,170"
                              " --lat -70,40 --size 160,80");
    expectPanorama(r, equirectFromHeader(r.header, 160, 80), (320.0 / 160) / (110.0 / 80));
  }
  {
    SCOPED_TRACE("fisheye");
    const Rendered r =
        render("fisheye",
               " --camera fisheye --eye 1,4,7 --dir 0,-0.5,-1 --fisheye-fov 200 --size 120,100");
    expectPanorama(r, fisheyeFromHeader(r.header), 1.0);
  }
}

TEST(ExrHeaders, ReadExrReturnsTheStandardAndPanoramaAttributes) {
  const std::string dir = test::scratchDir();
  std::string out;
  ASSERT_EQ(test::runCommand(test::apertureBinary() +
                                 " render --quiet --aov depth --camera fisheye --fisheye-fov 190"
                                 " --size 90,60 --eye 1,4,7 --dir 0,-0.5,-1 --out " +
                                 dir + "/f.exr",
                             &out),
            0)
      << out;
  ExrMetadata meta;
  readExr(dir + "/f.exr", &meta);
  EXPECT_FALSE(meta.camera.ndcFromWorld.has_value());
  EXPECT_FALSE(meta.camera.equirect.has_value());
  ASSERT_TRUE(meta.camera.fisheye.has_value());
  EXPECT_EQ(meta.camera.fisheye->fovDeg, 190.0);
  EXPECT_EQ(meta.camera.fisheye->centerPx, glm::dvec2(45, 30));
  EXPECT_EQ(meta.camera.fisheye->radiusPx, 30.0);
  EXPECT_EQ(meta.camera.pixelAspectRatio, 1.0);

  ASSERT_EQ(
      test::runCommand(test::apertureBinary() +
                           " render --quiet --aov depth --d 2 --viewport 2.4,1.8 --shift 0.1,0"
                           " --size 160,90 --eye 6,5,9 --at 0,0.5,0 --out " +
                           dir + "/p.exr",
                       &out),
      0)
      << out;
  readExr(dir + "/p.exr", &meta);
  ASSERT_TRUE(meta.camera.ndcFromWorld.has_value());
  EXPECT_FALSE(meta.camera.fisheye.has_value());
  EXPECT_NEAR(meta.camera.pixelAspectRatio, 0.75, 1e-7);  // float in the file
  EXPECT_NEAR(meta.camera.screenWindowWidth, 1.2, 1e-7);
  EXPECT_NEAR(meta.camera.screenWindowCenter.x, 0.12, 1e-7);
}

}  // namespace
}  // namespace aperture
