#pragma once
// `aperture bench`'s measurements: Mrays/s of the frame loop beside the bare-Embree baseline,
// build time, load speed, memory and the sweeps, with the configuration printed beside every
// number (stdout, and JSON with --json). Its flags: apps/cli/cmd_bench.cpp.
#include <string>

#include "apps/services/render_options.h"
#include "apps/services/scene_setup.h"
#include "bench/measure/bench_scaling.h"
#include "cameras/schema/param_schema.h"

namespace aperture::app {

/// One bench run as the command line gives it.
struct BenchRequest {
  SceneOptions scene;
  ParamSet camera;              ///< the camera parameters given, with their sources
  CameraParams cameraDefaults;  ///< what the command's defaults fill in
  RenderOptions render;
  int frames = 10, warmup = 3, builds = 3;
  bool baseline = false, quiet = false;
  bool scaling = false;  ///< --scaling: procedural sizes, each in a child bench (bench_scaling.h)
  std::string scalingSizes = kDefaultScalingSizes;
  bool nullTrace = false;   ///< --null: the frame loop without Embree (RenderSettings::nullTrace)
  bool noSceneBox = false;  ///< --no-scene-box: RenderSettings::sceneBoxTest off
  bool noCoverageMask = false;  ///< --no-coverage-mask: RenderSettings::coverageMask off
  std::string sweep, json, preset;
  std::string layersMethod;  ///< hidden --layers-method filter|retrace (bench/layers_methods.sh)
  std::string baselineApi = "packet16";  ///< --baseline-api (BaselineApi)
};

/// Runs it; throws Error for a bad request before loading anything. Returns the exit code.
int runBench(const BenchRequest& a);

}  // namespace aperture::app
