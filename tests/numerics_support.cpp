#include "tests/numerics_support.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "cameras/registry/registry.h"

namespace aperture::test {

Device& numericsDevice() {
  static Device d;
  return d;
}

Loaded load(const std::string& spec, const LoadOptions& lo, const BuildOptions& bo) {
  return sceneOf(loadMesh(spec, lo), bo);
}

Loaded sceneOf(Mesh m, const BuildOptions& bo) {
  Loaded l;
  l.mesh = std::make_unique<Mesh>(std::move(m));
  l.scene = std::make_unique<Scene>(numericsDevice(), std::vector<const Mesh*>{l.mesh.get()}, bo);
  return l;
}

Framebuffer render(const Scene& scene, const CameraParams& p, AovSet aovs, RenderStats* stats,
                   RenderSettings settings) {
  const auto cam = makeCamera(p, scene.renderOrigin());
  Framebuffer fb(p.width, p.height, aovs);
  settings.spp = p.spp;
  const RenderStats s = renderImage(scene, *cam, settings, fb);
  if (stats) *stats = s;
  return fb;
}

CameraParams calibratedOpenCvLike(const CameraParams& p) {
  CameraParams c = p;
  c.type = "calibrated";
  c.fovDeg.reset();
  c.intrinsics = std::vector<double>{50.0, 52.0, 30.0, 21.0};
  c.lensModel = "OPENCV";
  c.distortion = std::vector<double>{-0.1, 0.01, 1e-4, -1e-4};
  return c;
}

std::vector<SceneObject> placedTwice(const Mesh& mesh, const glm::dvec3& offset) {
  SceneObject first{&mesh}, second{&mesh};
  second.worldFromMesh = glm::translate(glm::dmat4(1.0), offset) *
                         glm::rotate(glm::dmat4(1.0), 0.7, glm::dvec3(0.3, 1.0, 0.2));
  return {first, second};
}

CameraParams lookAt(glm::dvec3 eye, glm::dvec3 at, int w, int h) {
  CameraParams p;
  p.eye = eye;
  p.at = at;
  p.width = w;
  p.height = h;
  p.fovDeg = 40;
  return p;
}

double relErr(double got, double want) { return std::abs(got - want) / std::abs(want); }

Agreement compare(const Framebuffer& a, const Framebuffer& ref) {
  Agreement g;
  size_t same = 0;
  for (size_t i = 0; i < ref.pixelCount(); ++i) {
    if (a.primId[i] != ref.primId[i]) continue;
    ++same;
    if (ref.primId[i] == kInvalidId) continue;
    g.maxZ = std::max(g.maxZ, relErr(a.depth[i], ref.depth[i]));
    g.maxT = std::max(g.maxT, relErr(a.distance[i], ref.distance[i]));
  }
  g.primIdShare = double(same) / double(ref.pixelCount());
  return g;
}

}  // namespace aperture::test
