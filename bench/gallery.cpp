// Renders procedural:city with every camera model and writes PNGs (docs/gallery/ by default):
//   aperture_gallery [OUTPUT_DIR]
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/aov/framebuffer.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/io/image.h"
#include "core/mesh/mesh.h"

namespace aperture {
namespace {

struct Shot {
  std::string file;
  CameraParams params;
};

CameraParams base(const char* type, glm::dvec3 eye, int w = 480, int h = 360) {
  CameraParams p;
  p.type = type;
  p.eye = eye;
  p.width = w;
  p.height = h;
  return p;
}

std::vector<Shot> shots() {
  constexpr double kRadPerDeg = 0.017453292519943295769;
  std::vector<Shot> s;
  // Foreshortening: down a street lined with columns, sizes shrink with depth.
  CameraParams street = base("perspective", {-10.5, 1.2, 5.0});
  street.at = glm::dvec3(10.0, 2.2, 5.0);
  street.fovDeg = 70;
  s.push_back({"foreshortening.png", street});
  // Tilted up 30°: converging verticals; the same view with --architectural: parallel ones.
  CameraParams tilt = base("perspective", {0.0, 1.0, 13.0});
  tilt.dir = glm::dvec3(0.0, std::sin(30 * kRadPerDeg), -std::cos(30 * kRadPerDeg));
  tilt.fovDeg = 70;
  s.push_back({"tilted.png", tilt});
  tilt.architectural = true;
  s.push_back({"architectural.png", tilt});
  // The same frame as orthographic and as oblique (depth recedes up and to the right); the
  // oblique eye moves by tan(angle)·depth so the city stays in the picture.
  CameraParams front = base("orthographic", {0.0, 8.0, 16.0});
  front.dir = glm::dvec3(0.0, -0.35, -1.0);
  front.viewport = glm::dvec2(26.0, 19.5);
  s.push_back({"orthographic.png", front});
  front.type = "oblique";
  front.obliqueAnglesDeg = glm::dvec2(-30.0, -15.0);
  front.eye += glm::dvec3(9.0, 4.0, 0.0);
  s.push_back({"oblique.png", front});
  // Thin lens, 64 spp: focused on the nearest boxes, then on the far end of the city.
  CameraParams lens = base("thinlens", {-12.0, 2.2, 13.0});
  lens.at = glm::dvec3(0.0, 1.5, 0.0);
  lens.fovDeg = 50;
  lens.spp = 64;
  lens.apertureRadius = 0.35;
  lens.focusDistance = 7.0;
  s.push_back({"thinlens_near.png", lens});
  lens.focusDistance = 24.0;
  s.push_back({"thinlens_far.png", lens});
  // Full-sphere panorama from a street crossing, and a 180° fisheye looking straight up.
  CameraParams pano = base("equirect", {0.0, 1.7, 0.0}, 512, 256);
  pano.dir = glm::dvec3(0.0, 0.0, -1.0);
  s.push_back({"equirect.png", pano});
  CameraParams fish = base("fisheye", {0.0, 1.7, 0.0}, 360, 360);
  fish.dir = glm::dvec3(0.0, 1.0, 0.0);
  fish.up = glm::dvec3(0.0, 0.0, -1.0);
  fish.fisheyeFovDeg = 180;
  s.push_back({"fisheye.png", fish});
  return s;
}

int run(const std::string& outDir) {
  const Mesh city = loadMesh("procedural:city");
  Device device;
  Scene scene(device, {&city});
  for (const Shot& shot : shots()) {
    const auto camera = makeCamera(shot.params, scene.renderOrigin());
    RenderSettings settings;
    settings.spp = shot.params.spp;
    Framebuffer fb(shot.params.width, shot.params.height, kAovColor);
    const RenderStats stats = renderImage(scene, *camera, settings, fb);
    const std::string path = outDir + "/" + shot.file;
    writePreview(path, fb);
    std::printf("%-22s %-12s %dx%d spp %-3d %.2f s\n", shot.file.c_str(), shot.params.type.c_str(),
                shot.params.width, shot.params.height, shot.params.spp, stats.seconds);
  }
  return 0;
}

}  // namespace
}  // namespace aperture

int main(int argc, char** argv) {
  try {
    return aperture::run(argc > 1 ? argv[1] : "docs/gallery");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "aperture_gallery: %s\n", e.what());
    return 1;
  }
}
