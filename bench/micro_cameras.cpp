// Ray generation cost per camera model and packet width (rays/s), so camera cost stays
// visible next to traversal cost. One 512x512 frame of packets per iteration.
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/packet.h"

namespace aperture {
namespace {

constexpr int kSize = 512;

CameraParams paramsFor(const std::string& type, int spp) {
  CameraParams p;
  p.type = type;
  p.width = p.height = kSize;
  p.spp = spp;
  p.eye = {1.0, 2.0, 8.0};
  p.at = glm::dvec3(0.0, 1.0, 0.0);
  p.fovDeg = 50;
  if (type == "orthographic" || type == "oblique") {
    p.fovDeg.reset();
    p.viewport = glm::dvec2(6.0, 6.0);
  }
  if (type == "oblique") p.obliqueAnglesDeg = glm::dvec2(30.0, 20.0);
  if (type == "thinlens") {
    p.apertureRadius = 0.1;
    p.focusDistance = 8.0;
  }
  if (type == "fisheye") p.fisheyeFovDeg = 180;
  if (type == "calibrated" || type == "calibrated-opencv") {
    // The perspective camera's K (fov 50° over 512 px), undistorted or with an OPENCV lens.
    p.type = "calibrated";
    const double f = 0.5 * kSize / std::tan(25.0 * 3.14159265358979323846 / 180.0);
    p.fovDeg.reset();
    p.intrinsics = std::vector<double>{f, f, 0.5 * kSize, 0.5 * kSize};
    if (type == "calibrated-opencv") {
      p.lensModel = "OPENCV";
      p.distortion = std::vector<double>{-0.1, 0.01, 1e-4, -1e-4};
    }
  }
  return p;
}

template <int N>
void generateFrame(benchmark::State& state, const std::string& type, int spp) {
  const auto camera = makeCamera(paramsFor(type, spp), glm::dvec3(0.5, 0.5, 0.5));
  alignas(64) typename PacketOf<N>::type packet;
  RayLanes lanes = rayLanes<N>(packet);
  alignas(64) int valid[16];
  const int bw = blockWidthFor(N), bh = blockHeightFor(N);
  for (auto _ : state) {
    for (int s = 0; s < spp; ++s)
      for (int y = 0; y < kSize; y += bh)
        for (int x = 0; x < kSize; x += bw) {
          camera->generate(PacketRequest{x, y, bw, bh, s}, lanes, valid);
          benchmark::DoNotOptimize(packet);
          benchmark::DoNotOptimize(valid);
        }
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kSize * kSize * spp);
  state.SetLabel(type + " width " + std::to_string(N) + " spp " + std::to_string(spp));
}

void registerAll() {
  for (const std::string type : {"perspective", "orthographic", "oblique", "thinlens", "equirect",
                                 "fisheye", "calibrated", "calibrated-opencv"})
    for (int spp : {1, 4}) {
      const std::string suffix = "/" + type + "/spp" + std::to_string(spp);
      benchmark::RegisterBenchmark(("CameraGenerate/w1" + suffix).c_str(),
                                   [=](benchmark::State& s) { generateFrame<1>(s, type, spp); });
      benchmark::RegisterBenchmark(("CameraGenerate/w4" + suffix).c_str(),
                                   [=](benchmark::State& s) { generateFrame<4>(s, type, spp); });
      benchmark::RegisterBenchmark(("CameraGenerate/w8" + suffix).c_str(),
                                   [=](benchmark::State& s) { generateFrame<8>(s, type, spp); });
      benchmark::RegisterBenchmark(("CameraGenerate/w16" + suffix).c_str(),
                                   [=](benchmark::State& s) { generateFrame<16>(s, type, spp); });
    }
}

const bool kRegistered = (registerAll(), true);

}  // namespace
}  // namespace aperture
