#pragma once
// Helpers of the numerics tests (tests/core/engine/test_numerics_*.cpp,
// tests/cameras/models/test_numerics_cameras.cpp): one shared device, a mesh with its scene,
// renders, and agreement of two renders.
#include <memory>
#include <string>
#include <vector>

#include "cameras/schema/params.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/units.h"

namespace aperture::test {

inline constexpr double kDeg = kRadPerDeg;

/// One Embree device for the tests that build scenes themselves.
Device& numericsDevice();

/// A loaded mesh and the scene over it (the mesh must outlive the scene).
struct Loaded {
  std::unique_ptr<Mesh> mesh;
  std::unique_ptr<Scene> scene;
};
Loaded load(const std::string& spec, const LoadOptions& lo = {}, const BuildOptions& bo = {});
/// `m` and the scene over it.
Loaded sceneOf(Mesh m, const BuildOptions& bo = {});

/// Renders `p` (its size and spp) into a fresh framebuffer of `aovs`, with `settings` (whose
/// spp is taken from `p`).
Framebuffer render(const Scene& scene, const CameraParams& p, AovSet aovs = parseAovList("all"),
                   RenderStats* stats = nullptr, RenderSettings settings = {});

/// A calibrated OPENCV camera (distorted, 50 px focal length) at the pose and size of `p`.
CameraParams calibratedOpenCvLike(const CameraParams& p);

/// `mesh` placed twice: once as loaded, once turned and moved by `offset` (an Embree instance).
std::vector<SceneObject> placedTwice(const Mesh& mesh, const glm::dvec3& offset);

/// A 40° perspective camera at `eye` looking at `at`, w x h pixels.
CameraParams lookAt(glm::dvec3 eye, glm::dvec3 at, int w, int h);

double relErr(double got, double want);

/// Agreement of two renders: share of pixels with equal primID and the largest relative Z / T
/// error over the pixels both hit on the same triangle.
struct Agreement {
  double primIdShare = 0, maxZ = 0, maxT = 0;
};
Agreement compare(const Framebuffer& a, const Framebuffer& ref);

}  // namespace aperture::test
