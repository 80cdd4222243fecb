// What a calibrated sensor with distortion costs before its first ray: its direction table,
// every pixel centre's ray by the lens's exact inverse (cameras/lenses/direction_table.h), at
// 1920x1080 (pixels/s). Paid once per sensor, so once per image where every image has its
// own intrinsics (COLMAP's default when it calibrates). Threads: TBB's default (all cores).
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "cameras/lenses/direction_table.h"

namespace aperture {
namespace {

struct TableCase {
  const char* name;
  LensModelId model;
  std::vector<double> params;  // COLMAP's order
};

// Moderate lenses of each family at a 1080p sensor's focal length (the kinds COLMAP and
// nerfstudio calibrate); none folds inside the image.
std::vector<TableCase> tableCases() {
  return {
      {"SIMPLE_RADIAL", LensModelId::SimpleRadial, {1500, 960, 540, -0.08}},
      {"RADIAL", LensModelId::Radial, {1500, 960, 540, -0.1, 0.01}},
      {"OPENCV", LensModelId::OpenCV, {1500, 1500, 960, 540, -0.1, 0.01, 1e-4, -1e-4}},
      {"FULL_OPENCV",
       LensModelId::FullOpenCV,
       {1500, 1500, 960, 540, -0.1, 0.01, 1e-4, -1e-4, 0.001, 0.01, 0.001, 1e-4}},
      {"OPENCV_FISHEYE", LensModelId::OpenCVFisheye, {600, 600, 960, 540, 0.05, -0.01, 0.001, 0}},
      {"THIN_PRISM_FISHEYE",
       LensModelId::ThinPrismFisheye,
       {600, 600, 960, 540, 0.05, -0.01, 1e-4, -1e-4, 0.001, 0, 1e-4, -1e-4}},
  };
}

void buildTable(benchmark::State& state, const TableCase& c) {
  CalibratedSensor sensor;
  sensor.width = 1920;
  sensor.height = 1080;
  sensor.lens = Lens(c.model, c.params);
  for (auto _ : state) {
    const DirectionTable table(sensor);  // the constructor: no cache
    benchmark::DoNotOptimize(table.x());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * sensor.width * sensor.height);
  state.SetLabel(std::string(c.name) + " 1920x1080");
}

void registerAll() {
  for (const TableCase& c : tableCases())
    benchmark::RegisterBenchmark((std::string("DirectionTable/") + c.name).c_str(),
                                 [c](benchmark::State& s) { buildTable(s, c); })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
}

const bool kRegistered = (registerAll(), true);

}  // namespace
}  // namespace aperture
