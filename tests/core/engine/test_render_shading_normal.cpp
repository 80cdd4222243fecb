// Shading normals (vertex normals interpolated with Embree's barycentrics) against the
// analytic normal of a sphere, directly attached, instanced with a non-uniform scale and
// mirrored by a negative load scale; the geometric-normal fallback; and the normal frames
// (opencv, opengl) against a rotation built here from the look-at vectors.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/units.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// A coarse UV sphere of radius 1 at the origin as ASCII PLY, with its analytic unit normals
/// (nx ny nz) when `normals`.
std::string spherePly(bool normals) {
  const int rings = 12, segments = 16;
  std::vector<glm::dvec3> v;
  v.push_back({0, 0, 1});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double theta = kPi * r / rings, phi = 2 * kPi * s / segments;
      v.push_back(
          {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)});
    }
  v.push_back({0, 0, -1});
  std::vector<std::vector<int>> f;
  auto ring = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) f.push_back({0, ring(1, s), ring(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s)
      f.push_back({ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1)});
  const int south = int(v.size()) - 1;
  for (int s = 0; s < segments; ++s)
    f.push_back({south, ring(rings - 1, s + 1), ring(rings - 1, s)});
  std::string ply =
      cat("ply\nformat ascii 1.0\nelement vertex ", v.size(),
          "\nproperty double x\nproperty double y\nproperty double z\n",
          normals ? "property float nx\nproperty float ny\nproperty float nz\n" : "",
          "element face ", f.size(), "\nproperty list uchar int vertex_indices\n", "end_header\n");
  char buf[160];
  for (const glm::dvec3& p : v) {
    std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g", p.x, p.y, p.z);
    ply += buf;
    if (normals) ply += std::string(" ") + buf;  // unit sphere: the normal is the position
    ply += "\n";
  }
  for (const auto& face : f) {
    ply += cat(face.size());
    for (int k : face) ply += cat(" ", k);
    ply += "\n";
  }
  return ply;
}

std::string writeSphere(bool normals) {
  const std::string path =
      test::scratchDir() + (normals ? "/sphere_normals.ply" : "/sphere_plain.ply");
  test::writeFile(path, spherePly(normals));
  return path;
}

CameraParams lookAt(glm::dvec3 eye, glm::dvec3 at, int size = 64) {
  CameraParams p;
  p.eye = eye;
  p.at = at;
  p.up = glm::dvec3(0, 1, 0);
  p.width = size;
  p.height = size;
  p.fovDeg = 40;
  return p;
}

Framebuffer render(const Scene& scene, const CameraParams& p, const std::string& aovs,
                   NormalFrame frame = NormalFrame::World) {
  const auto camera = makeCamera(p, scene.renderOrigin());
  Framebuffer fb(p.width, p.height, parseAovSet(aovs));
  RenderSettings rs;
  rs.normalFrame = frame;
  renderImage(scene, *camera, rs, fb);
  return fb;
}

glm::dvec3 at3(const std::vector<float>& v, size_t px) {
  return {v[3 * px], v[3 * px + 1], v[3 * px + 2]};
}

/// Angles (radians) of the shading and geometric normals from the analytic normal
/// `analytic(P)`, summed over the hit pixels; max of the shading one.
struct NormalErrors {
  double shadingSum = 0, geometricSum = 0, shadingMax = 0;
  int hits = 0;
};

template <typename F>
NormalErrors normalErrors(const Framebuffer& fb, F analytic) {
  NormalErrors e;
  for (size_t px = 0; px < fb.pixelCount(); ++px) {
    if (!std::isfinite(fb.depth[px])) continue;
    const glm::dvec3 n = glm::normalize(analytic(at3(fb.position, px)));
    const double s = std::acos(std::min(1.0, glm::dot(n, at3(fb.shadingNormal, px))));
    const double g = std::acos(std::min(1.0, glm::dot(n, at3(fb.normal, px))));
    e.shadingSum += s;
    e.geometricSum += g;
    e.shadingMax = std::max(e.shadingMax, s);
    ++e.hits;
  }
  return e;
}

void expectShadingCloserThanGeometric(const NormalErrors& e) {
  ASSERT_GT(e.hits, 500);
  // A facet's normal is up to half its angle (~7 degrees) off; interpolated normals are off
  // by the interpolation error only. A wrong corner order or no interpolation is degrees off.
  EXPECT_LT(e.shadingSum, 0.2 * e.geometricSum) << e.shadingSum << " vs " << e.geometricSum;
  EXPECT_LT(e.shadingMax, 0.03);
}

LoadOptions normalsOptions() {
  LoadOptions o;
  o.vertexNormals = true;
  return o;
}

TEST(ShadingNormal, InterpolatedVertexNormalsFollowTheSphere) {
  const Mesh mesh = loadMesh(writeSphere(true), normalsOptions());
  ASSERT_EQ(mesh.vertexNormals.size(), 3 * mesh.vertexCount);
  const Device device;
  const Scene scene(device, std::vector<const Mesh*>{&mesh});
  const Framebuffer fb =
      render(scene, lookAt({0.5, 0.8, 3.5}, {0, 0, 0}), "depth,position,normal,shading-normal");
  expectShadingCloserThanGeometric(normalErrors(fb, [](const glm::dvec3& p) { return p; }));
}

TEST(ShadingNormal, MirroredLoadKeepsNormalsOutward) {
  // scale -1: a point reflection. The inverse transpose keeps vertex normals outward; the
  // cofactor matrix (det · M^-T) would turn them inwards.
  LoadOptions o = normalsOptions();
  o.scale = -1.0;
  o.translate = glm::dvec3(0.5, 0, 0);
  const Mesh mesh = loadMesh(writeSphere(true), o);
  const Device device;
  const Scene scene(device, std::vector<const Mesh*>{&mesh});
  const glm::dvec3 centre(0.5, 0, 0);
  const Framebuffer fb =
      render(scene, lookAt({0.5, 0.3, 3.5}, centre), "depth,position,normal,shading-normal");
  const NormalErrors e = normalErrors(fb, [&](const glm::dvec3& p) { return p - centre; });
  EXPECT_LT(e.shadingMax, 0.03);
  EXPECT_GT(e.hits, 500);
}

TEST(ShadingNormal, InstancedNonUniformScaleUsesTheInverseTranspose) {
  const Mesh mesh = loadMesh(writeSphere(true), normalsOptions());
  const Device device;
  // Placed twice, so Embree instances it; an ellipsoid with semi-axes 1.5, 0.7, 1.
  glm::dmat4 a(1.0), b(1.0);
  a[0][0] = 1.5, a[1][1] = 0.7;
  a[3] = glm::dvec4(-1.2, 0, 0, 1);
  b = a;
  b[3] = glm::dvec4(1.8, 0, 0, 1);
  const Scene scene(device, std::vector<SceneObject>{{&mesh, a}, {&mesh, b}});
  ASSERT_EQ(scene.instanceCount(), 2u);
  const Framebuffer fb = render(scene, lookAt({-1.2, 0.4, 4.0}, {-1.2, 0, 0}, 80),
                                "depth,position,normal,shading-normal,geomid");
  // The ellipsoid's normal at world P: M^-T (M^-1 (P - t)) for the placement it belongs to.
  const Framebuffer& f = fb;
  NormalErrors e;
  for (size_t px = 0; px < f.pixelCount(); ++px) {
    if (!std::isfinite(f.depth[px])) continue;
    const glm::dmat4& m = f.geomId[px] == 0 ? a : b;
    const glm::dmat3 linear(m);
    const glm::dvec3 local = glm::inverse(linear) * (at3(f.position, px) - glm::dvec3(m[3]));
    const glm::dvec3 n = glm::normalize(glm::transpose(glm::inverse(linear)) * local);
    const double s = std::acos(std::min(1.0, glm::dot(n, at3(f.shadingNormal, px))));
    const double g = std::acos(std::min(1.0, glm::dot(n, at3(f.normal, px))));
    e.shadingSum += s, e.geometricSum += g, e.shadingMax = std::max(e.shadingMax, s), ++e.hits;
  }
  expectShadingCloserThanGeometric(e);
}

TEST(ShadingNormal, WithoutVertexNormalsItIsTheGeometricNormal) {
  const Mesh mesh = loadMesh(writeSphere(false), normalsOptions());
  EXPECT_TRUE(mesh.vertexNormals.empty());
  const Device device;
  const Scene scene(device, std::vector<const Mesh*>{&mesh});
  const Framebuffer fb =
      render(scene, lookAt({0, 0, 3.5}, {0, 0, 0}), "depth,normal,shading-normal");
  int hits = 0;
  for (size_t px = 0; px < fb.pixelCount(); ++px) {
    if (!std::isfinite(fb.depth[px])) {
      EXPECT_EQ(at3(fb.shadingNormal, px), glm::dvec3(0.0));
      continue;
    }
    EXPECT_EQ(at3(fb.shadingNormal, px), at3(fb.normal, px));
    ++hits;
  }
  EXPECT_GT(hits, 500);
}

/// The camera-frame rotation of a look-at camera, built here from eye, at and up: rows
/// x, y, z of the frame in world space.
glm::dmat3 rowsOf(const glm::dvec3& x, const glm::dvec3& y, const glm::dvec3& z) {
  return glm::transpose(glm::dmat3(x, y, z));
}

TEST(NormalFrame, OpenCvAndOpenGlNormalsAreTheWorldNormalsRotatedIntoTheCamera) {
  const Mesh mesh = loadMesh(writeSphere(true), normalsOptions());
  const Device device;
  const Scene scene(device, std::vector<const Mesh*>{&mesh});
  const glm::dvec3 eye(1.0, 1.5, 3.0), at(0.1, 0.0, 0.0), up(0, 1, 0);
  const CameraParams p = lookAt(eye, at);
  const glm::dvec3 w = glm::normalize(eye - at);  // backwards
  const glm::dvec3 u = glm::normalize(glm::cross(up, w));
  const glm::dvec3 v = glm::cross(w, u);
  const Framebuffer world = render(scene, p, "depth,normal,shading-normal");
  struct Case {
    NormalFrame frame;
    glm::dmat3 rotation, yFlipped;
  };
  for (const Case& c : {Case{NormalFrame::OpenCV, rowsOf(u, -v, -w), rowsOf(u, v, -w)},
                        Case{NormalFrame::OpenGL, rowsOf(u, v, w), rowsOf(u, -v, w)}}) {
    const Framebuffer cam = render(scene, p, "depth,normal,shading-normal", c.frame);
    int hits = 0, flippedMatches = 0;
    for (size_t px = 0; px < world.pixelCount(); ++px) {
      if (!std::isfinite(world.depth[px])) continue;
      ++hits;
      for (const std::vector<float> Framebuffer::*aov :
           {&Framebuffer::normal, &Framebuffer::shadingNormal}) {
        const glm::dvec3 want = c.rotation * at3(world.*aov, px);
        const glm::dvec3 got = at3(cam.*aov, px);
        EXPECT_LT(glm::length(got - want), 1e-5) << normalFrameName(c.frame) << " pixel " << px;
        flippedMatches += glm::length(got - c.yFlipped * at3(world.*aov, px)) < 1e-3;
      }
      // Facing the camera: OpenCV z (forward) is negative, OpenGL z (backwards) positive.
      const double z = at3(cam.shadingNormal, px).z;
      EXPECT_TRUE(c.frame == NormalFrame::OpenCV ? z < 0.05 : z > -0.05) << px << " " << z;
    }
    EXPECT_GT(hits, 500);
    // The y-flipped rotation matches only where the normal's y vanishes.
    EXPECT_LT(flippedMatches, hits / 10) << normalFrameName(c.frame);
  }
  // The helper itself, for a described camera.
  const CameraDescription d = makeCamera(p)->describe();
  const glm::dmat3 r = normalFrameFromWorld(NormalFrame::OpenCV, d);
  EXPECT_LT(glm::length(r * (-w) - glm::dvec3(0, 0, 1)), 1e-9);  // forward is +z
  EXPECT_LT(glm::length(r * v - glm::dvec3(0, -1, 0)), 1e-9);    // up is -y
  EXPECT_EQ(normalFrameFromWorld(NormalFrame::World, d), glm::dmat3(1.0));
  EXPECT_THROW(parseNormalFrame("opencvv"), Error);
}

TEST(ShadingNormal, ObjVertexNormalsFollowTheirFaceCorners) {
  // Two triangles share vertices 1 and 3 (OBJ, 1-based) but give vertex 3 different normals
  // (vn 2 in the first face, vn 3 in the second): the loader must give each corner its own
  // normal (splitting vertex 3), keep the triangle order and the corner positions.
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
      "vn 0 0 1\nvn 0.6 0 0.8\nvn 0 0.6 0.8\n"
      "f 1//1 2//1 3//2\nf 2//1 4//1 3//3\n";
  LoadOptions wantNormals;
  wantNormals.vertexNormals = true;
  wantNormals.placement = Placement::WorldSpace;
  Mesh m = loadObjFromMemory(obj.data(), obj.size(), "two.obj", wantNormals);
  finishMesh(m, wantNormals);
  ASSERT_EQ(m.triangleCount(), 2u);
  ASSERT_EQ(m.vertexNormals.size(), 3 * m.vertexCount);
  // Expected per corner, read off the text above: position index and normal, 0-based.
  const int cornerPosition[6] = {0, 1, 2, 1, 3, 2};
  const glm::vec3 normals[3] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, 0.6f, 0.8f}};
  const int cornerNormal[6] = {0, 0, 1, 0, 0, 2};
  const glm::vec3 positions[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  for (int c = 0; c < 6; ++c) {
    const uint32_t v = m.indices[size_t(c)];
    EXPECT_EQ(m.vertex(v), positions[cornerPosition[c]]) << "corner " << c;
    const glm::vec3 n(m.vertexNormals[3 * v], m.vertexNormals[3 * v + 1],
                      m.vertexNormals[3 * v + 2]);
    EXPECT_EQ(n, normals[cornerNormal[c]]) << "corner " << c;
  }
  // Without the option nothing is stored and the vertices are not split.
  Mesh plain = loadObjFromMemory(obj.data(), obj.size(), "two.obj", {});
  EXPECT_TRUE(plain.vertexNormals.empty());
  EXPECT_EQ(plain.vertexCount, 4u);
}

}  // namespace
}  // namespace aperture
