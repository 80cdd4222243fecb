// The surface AOVs (instance, mesh, material, barycentric, uv, vertex-color, albedo) of a
// hand-built scene: a textured, coloured quad of two triangles with face groups and materials,
// attached directly, and a bare triangle placed twice (instanced) with ids of its own. Every
// hit pixel's values are worked out here from the rendered world position: the triangle that
// holds it, its barycentric weights from the triangle's world vertices, and the texture's
// texel (nearest, repeat) sRGB-decoded by the formula, never by the sampler under test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/io/image.h"
#include "core/io/image_codec.h"
#include "core/io/texture_sampler.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;

namespace {

constexpr int kCheckerW = 4, kCheckerH = 4;

/// Texel (x, y) of the albedo test texture, y = 0 the top row: a checkerboard of two colours
/// with a distinct red per column and green per row, so that any flip or shift shows.
std::array<uint8_t, 3> checkerTexel(int x, int y) {
  const bool dark = ((x + y) & 1) != 0;
  return {uint8_t(40 + 50 * x), uint8_t(30 + 60 * y), uint8_t(dark ? 20 : 230)};
}

double srgbDecodeRef(double c) {
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

/// The nearest, repeating texel at (s, t) as linear RGBA.
glm::dvec4 checkerAt(double s, double t) {
  const auto wrap = [](double c, int n) {
    return std::min(n - 1, int(std::floor((c - std::floor(c)) * n)));
  };
  const auto b = checkerTexel(wrap(s, kCheckerW), wrap(t, kCheckerH));
  return {srgbDecodeRef(b[0] / 255.0), srgbDecodeRef(b[1] / 255.0), srgbDecodeRef(b[2] / 255.0),
          1.0};
}

/// Distance of (s, t) from the nearest texel edge, in texels: pixels near an edge are skipped
/// (which texel a float lookup lands in is not decided there).
double texelEdgeDistance(double s, double t) {
  const auto d = [](double c, int n) {
    const double x = c * n;
    return std::fabs(x - std::round(x));
  };
  return std::min(d(s, kCheckerW), d(t, kCheckerH));
}

std::string writeCheckerPng() {
  std::vector<uint8_t> pixels;
  for (int y = 0; y < kCheckerH; ++y)
    for (int x = 0; x < kCheckerW; ++x)
      for (uint8_t v : checkerTexel(x, y)) pixels.push_back(v);
  ImageToEncode image;
  image.width = kCheckerW, image.height = kCheckerH, image.channels = 3;
  image.pixels = pixels.data();
  const std::string path = test::scratchDir() + "/albedo_checker.png";
  const std::vector<unsigned char> bytes = encodeImage(path, image);
  test::writeFile(path, std::string(bytes.begin(), bytes.end()));
  return path;
}

/// A mesh from vertices in its own space (no loader involved), anchored at the origin.
Mesh surfaceMesh(const std::vector<glm::dvec3>& verts, const std::vector<uint32_t>& idx) {
  Mesh m;
  m.name = "surface-test";
  m.vertexCount = verts.size();
  for (const auto& v : verts)
    for (int c = 0; c < 3; ++c) m.positions.push_back(float(v[c]));
  m.positions.resize(m.positions.size() + kVertexPaddingFloats, 0.0f);
  m.indices.assign(idx.begin(), idx.end());
  return m;
}

/// The test scene's data: the quad (object 0) and the triangle placed twice (objects 1, 2).
struct SurfaceScene {
  Mesh quad, tri;
  glm::dmat4 triA{1.0}, triB{1.0};
  ObjectIds quadIds{10, 3, 1}, triIdsA{20, 4, 0}, triIdsB{21, 4, 0};
  std::vector<Material> materials;

  SurfaceScene() {
    // The quad: x in [-2, 0], y in [-1, 1], z = 0, facing +z; texture coordinates run 0..2 in
    // s (so the texture repeats) and 0..1 in t, t = 0 at the top edge (y = 1).
    quad = surfaceMesh({{-2, -1, 0}, {0, -1, 0}, {0, 1, 0}, {-2, 1, 0}}, {0, 1, 2, 0, 2, 3});
    quad.texcoords = {0, 1, 2, 1, 2, 0, 0, 0};
    quad.vertexColors = {1,    0.2f, 0.4f, 1,    0.3f, 1,    0.5f, 0.8f,
                         0.6f, 0.7f, 1,    0.6f, 0.9f, 0.9f, 0.1f, 1};
    quad.faceGroups = {0, 4};
    quad.faceMaterials = {0, 1};
    // The triangle: no texture coordinates, no colours, no groups, no per-face materials.
    tri = surfaceMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2});
    triA[3] = glm::dvec4(0.5, -1.5, 0.2, 1);
    triB[0][0] = triB[1][1] = 1.2;
    triB[3] = glm::dvec4(0.5, 0.2, -0.3, 1);
    // Material 0 (the triangles): untextured. 1, 2 (the quad's faces): textured.
    materials.resize(3);
    materials[0].name = "plain", materials[0].baseColor = {0.5f, 0.25f, 1.0f, 1.0f};
    materials[1].name = "checker", materials[1].baseColorTexture = 0;
    materials[2].name = "tinted", materials[2].baseColor = {0.5f, 1.0f, 0.5f, 0.75f};
    materials[2].baseColorTexture = 0;
  }

  std::vector<SceneObject> objects() const {
    return {{&quad, glm::dmat4(1.0), nullptr, quadIds},
            {&tri, triA, nullptr, triIdsA},
            {&tri, triB, nullptr, triIdsB}};
  }

  std::shared_ptr<const SurfaceLooks> looks() const {
    auto l = std::make_shared<SurfaceLooks>();
    l->materials = materials;
    SurfaceTexture t;
    t.where = "test: checker";
    t.path = writeCheckerPng();
    t.nearest = true;
    l->textures = openTextureSampler({t});
    return l;
  }
};

/// What a pixel should hold, worked out from its world hit point.
struct ExpectedSurface {
  bool hit = false;
  uint32_t instance = kInvalidId, mesh = kInvalidId, material = kInvalidId;
  glm::dvec2 bary{0.0}, uv{0.0};
  glm::dvec4 color{0.0}, albedo{0.0};
  double edge = 1;  ///< smallest barycentric weight: near 0, the pixel lies on an edge
};

/// Barycentric weights of p (projected on the xy plane) in triangle a, b, c.
glm::dvec3 weightsXY(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                     const glm::dvec3& c) {
  const double den = (b.y - c.y) * (a.x - c.x) + (c.x - b.x) * (a.y - c.y);
  const double wa = ((b.y - c.y) * (p.x - c.x) + (c.x - b.x) * (p.y - c.y)) / den;
  const double wb = ((c.y - a.y) * (p.x - c.x) + (a.x - c.x) * (p.y - c.y)) / den;
  return {wa, wb, 1 - wa - wb};
}

ExpectedSurface expectedAt(const SurfaceScene& s, const glm::dvec3& p) {
  ExpectedSurface e;
  const auto world = [](const Mesh& m, const glm::dmat4& place, uint32_t k) {
    return glm::dvec3(place * glm::dvec4(glm::dvec3(m.vertex(k)), 1.0));
  };
  struct Placed {
    const Mesh* mesh;
    glm::dmat4 place;
    ObjectIds ids;
  };
  const Placed placed[] = {{&s.quad, glm::dmat4(1.0), s.quadIds},
                           {&s.tri, s.triA, s.triIdsA},
                           {&s.tri, s.triB, s.triIdsB}};
  for (const Placed& o : placed) {
    const Mesh& m = *o.mesh;
    for (uint32_t t = 0; t < m.triangleCount(); ++t) {
      const uint32_t* c = &m.indices[3 * t];
      const glm::dvec3 a = world(m, o.place, c[0]), b = world(m, o.place, c[1]),
                       d = world(m, o.place, c[2]);
      const glm::dvec3 w = weightsXY(p, a, b, d);
      if (std::min({w.x, w.y, w.z}) < -1e-4) continue;
      if (std::fabs(w.x * a.z + w.y * b.z + w.z * d.z - p.z) > 1e-4) continue;
      e.hit = true;
      e.edge = std::min({w.x, w.y, w.z});
      e.instance = o.ids.instance + (m.faceGroups.empty() ? 0 : m.faceGroups[t]);
      e.mesh = o.ids.mesh;
      e.material = o.ids.materialBase + (m.faceMaterials.empty() ? 0 : m.faceMaterials[t]);
      e.bary = {w.y, w.z};
      e.color = glm::dvec4(1.0);
      if (!m.texcoords.empty()) {
        e.uv = glm::dvec2(0.0);
        for (int k = 0; k < 3; ++k)
          e.uv += w[k] * glm::dvec2(m.texcoords[2 * c[k]], m.texcoords[2 * c[k] + 1]);
      }
      if (!m.vertexColors.empty()) {
        e.color = glm::dvec4(0.0);
        for (int k = 0; k < 3; ++k)
          e.color += w[k] * glm::dvec4(m.vertexColors[4 * c[k]], m.vertexColors[4 * c[k] + 1],
                                       m.vertexColors[4 * c[k] + 2], m.vertexColors[4 * c[k] + 3]);
      }
      const Material& mat = s.materials[e.material];
      e.albedo = glm::dvec4(mat.baseColor) * e.color;
      if (mat.baseColorTexture >= 0) e.albedo *= checkerAt(e.uv.x, e.uv.y);
      return e;
    }
  }
  return e;
}

CameraParams surfaceCamera(int spp = 1) {
  CameraParams p;
  p.eye = {0, 0, 6};
  p.at = glm::dvec3(0, 0, 0);
  p.width = p.height = 64;
  p.fovDeg = 45;
  p.spp = spp;
  return p;
}

constexpr const char* kSurfaceAovList =
    "depth,position,primid,instance,mesh,material,barycentric,uv,vertex-color,albedo";

Framebuffer renderSurface(const Scene& scene, const std::string& aovs, int packetWidth = 16,
                          int spp = 1) {
  const CameraParams p = surfaceCamera(spp);
  auto camera = makeCamera(p, scene.renderOrigin());
  Framebuffer fb(p.width, p.height, parseAovSet(aovs));
  RenderSettings rs;
  rs.packetWidth = packetWidth;
  rs.spp = spp;
  renderImage(scene, *camera, rs, fb);
  return fb;
}

/// Checks every pixel of `fb` against expectedAt; returns the hit pixels checked.
int checkSurfacePixels(const SurfaceScene& s, const Framebuffer& fb) {
  int checked = 0, misses = 0;
  for (size_t px = 0; px < fb.pixelCount(); ++px) {
    if (!std::isfinite(fb.depth[px])) {
      ++misses;
      EXPECT_EQ(fb.instanceId[px], kInvalidId);
      EXPECT_EQ(fb.meshId[px], kInvalidId);
      EXPECT_EQ(fb.materialId[px], kInvalidId);
      for (int c = 0; c < 2; ++c) EXPECT_EQ(fb.barycentric[2 * px + size_t(c)], 0.0f);
      for (int c = 0; c < 2; ++c) EXPECT_EQ(fb.uv[2 * px + size_t(c)], 0.0f);
      for (int c = 0; c < 4; ++c) EXPECT_EQ(fb.vertexColor[4 * px + size_t(c)], 0.0f);
      for (int c = 0; c < 4; ++c) EXPECT_EQ(fb.albedo[4 * px + size_t(c)], 0.0f);
      continue;
    }
    const glm::dvec3 p(fb.position[3 * px], fb.position[3 * px + 1], fb.position[3 * px + 2]);
    const ExpectedSurface e = expectedAt(s, p);
    EXPECT_TRUE(e.hit) << "a hit at " << p.x << " " << p.y << " " << p.z << " on no triangle";
    if (!e.hit || e.edge < 1e-3) continue;  // on an edge: which triangle is not decided
    if (e.material > 0 && texelEdgeDistance(e.uv.x, e.uv.y) < 1e-3) continue;
    ++checked;
    const std::string at = cat("pixel ", px % 64, ", ", px / 64, " at ", p.x, " ", p.y, " ", p.z);
    EXPECT_EQ(fb.instanceId[px], e.instance) << at;
    EXPECT_EQ(fb.meshId[px], e.mesh) << at;
    EXPECT_EQ(fb.materialId[px], e.material) << at;
    for (int c = 0; c < 2; ++c) {
      EXPECT_NEAR(fb.barycentric[2 * px + size_t(c)], e.bary[c], 2e-5) << at;
      EXPECT_NEAR(fb.uv[2 * px + size_t(c)], e.uv[c], 5e-5) << at;
    }
    for (int c = 0; c < 4; ++c) {
      EXPECT_NEAR(fb.vertexColor[4 * px + size_t(c)], e.color[c], 5e-5) << at;
      EXPECT_NEAR(fb.albedo[4 * px + size_t(c)], e.albedo[c], 5e-5) << at;
    }
  }
  EXPECT_GT(misses, 100);
  return checked;
}

TEST(SurfaceAovs, EveryPixelMatchesTheTriangleItShows) {
  const SurfaceScene s;
  const Device device;
  Scene scene(device, s.objects());
  ASSERT_EQ(scene.instanceCount(), 2u);
  scene.setLooks(s.looks());
  for (int width : {1, 4, 8, 16}) {
    SCOPED_TRACE(cat("packet width ", width));
    const Framebuffer fb = renderSurface(scene, kSurfaceAovList, width);
    const int checked = checkSurfacePixels(s, fb);
    EXPECT_GT(checked, 800);
    // Every id shows up: the quad's two groups and materials, both placements of the triangle.
    for (uint32_t id : {10u, 14u, 20u, 21u})
      EXPECT_NE(std::find(fb.instanceId.begin(), fb.instanceId.end(), id), fb.instanceId.end())
          << "instance " << id;
    for (uint32_t id : {0u, 1u, 2u})
      EXPECT_NE(std::find(fb.materialId.begin(), fb.materialId.end(), id), fb.materialId.end())
          << "material " << id;
  }
}

// A flipped texture convention (t -> 1 - t) or Embree's u, v taken as the first two weights
// would fail the comparison above: the expectation here is not symmetric in either.
TEST(SurfaceAovs, TheExpectationsTellFlipsApart) {
  const SurfaceScene s;
  int differ = 0, weights = 0;
  for (double x = -1.95; x < 0; x += 0.1)
    for (double y = -0.95; y < 1; y += 0.1) {
      const ExpectedSurface e = expectedAt(s, {x, y, 0});
      ASSERT_TRUE(e.hit);
      if (glm::length(checkerAt(e.uv.x, e.uv.y) - checkerAt(e.uv.x, 1 - e.uv.y)) > 1e-3) ++differ;
      if (std::fabs(e.bary.x - (1 - e.bary.x - e.bary.y)) > 1e-3) ++weights;
    }
  EXPECT_GT(differ, 300);
  EXPECT_GT(weights, 300);
}

// The geometry AOVs come from the pixel-centre ray at any spp: spp 4 gives spp 1's values.
TEST(SurfaceAovs, CentreRayAtAnySpp) {
  const SurfaceScene s;
  const Device device;
  Scene scene(device, s.objects());
  scene.setLooks(s.looks());
  const Framebuffer one = renderSurface(scene, kSurfaceAovList, 8, 1);
  const Framebuffer four = renderSurface(scene, std::string(kSurfaceAovList) + ",color", 8, 4);
  EXPECT_EQ(one.instanceId, four.instanceId);
  EXPECT_EQ(one.materialId, four.materialId);
  EXPECT_EQ(one.barycentric, four.barycentric);
  EXPECT_EQ(one.albedo, four.albedo);
}

TEST(SurfaceAovs, RefusedWhenTheSceneLacksWhatTheyRead) {
  SurfaceScene s;
  const Device device;
  {
    Mesh bare = s.quad;
    bare.texcoords.clear(), bare.vertexColors.clear();
    const Scene scene(device, std::vector<const Mesh*>{&bare});
    EXPECT_NE(test::errorOf([&] { renderSurface(scene, "uv"); }).find("texture coordinates"),
              std::string::npos);
    EXPECT_NE(test::errorOf([&] { renderSurface(scene, "vertex-color"); }).find("vertex colours"),
              std::string::npos);
    EXPECT_NE(test::errorOf([&] { renderSurface(scene, "albedo"); }).find("no materials"),
              std::string::npos);
    // Ids and barycentrics need nothing but the triangles.
    EXPECT_NO_THROW(renderSurface(scene, "instance,mesh,material,barycentric"));
  }
  {
    SurfaceScene unsupported;
    unsupported.materials[2].unsupported = "KHR_texture_basisu";
    Scene scene(device, unsupported.objects());
    scene.setLooks(unsupported.looks());
    const std::string error = test::errorOf([&] { renderSurface(scene, "albedo"); });
    EXPECT_NE(error.find("KHR_texture_basisu"), std::string::npos) << error;
    EXPECT_NE(error.find("tinted"), std::string::npos) << error;
  }
  {
    // The triangle's material textured, and it has no texture coordinates.
    SurfaceScene textured;
    textured.materials[0].baseColorTexture = 0;
    Scene scene(device, textured.objects());
    scene.setLooks(textured.looks());
    const std::string error = test::errorOf([&] { renderSurface(scene, "albedo"); });
    EXPECT_NE(error.find("no texture coordinates"), std::string::npos) << error;
    EXPECT_NE(error.find("'plain'"), std::string::npos) << error;
    EXPECT_NO_THROW(renderSurface(scene, "uv,vertex-color"));
  }
  {
    SurfaceScene beyond;
    beyond.quadIds.materialBase = 2;  // uses 2 and 3 of 3 materials
    Scene scene(device, beyond.objects());
    scene.setLooks(beyond.looks());
    EXPECT_NE(test::errorOf([&] { renderSurface(scene, "albedo"); }).find("uses material 3"),
              std::string::npos);
  }
}

// --preview of a frame with albedo shows albedo, even beside color; the ids preview as hashed
// colours after the older rows.
TEST(SurfaceAovs, PreviewShowsAlbedoFirst) {
  EXPECT_EQ(previewAov(kAovAlbedo), kAovAlbedo);
  EXPECT_EQ(previewAov(kAovAlbedo | kAovColor | kAovDepth), kAovAlbedo);
  EXPECT_EQ(previewAov(kAovColor | kAovInstanceId), kAovColor);
  EXPECT_EQ(previewAov(kAovGeomId | kAovMaterialId), kAovGeomId);
  EXPECT_EQ(previewAov(kAovMeshId), kAovMeshId);
  EXPECT_EQ(previewAov(kAovUv | kAovBarycentric | kAovVertexColor), Aov(0));
}

}  // namespace
