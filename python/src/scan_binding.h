#pragma once
// Scene.scan's half that does not depend on which Scene traces: its arguments checked and
// converted (scanCallOf), and the sweeps traced through a scene and handed to NumPy
// (scanArrays). The Scene (scene_binding.cpp) first loads what the scan needs
// (app::withScanNeeds) into its own scene, so a scan honours every option it was built with.
#include <nanobind/nanobind.h>

#include <optional>
#include <string>
#include <vector>

#include "apps/services/scan.h"

namespace aperture::python {

namespace nb = nanobind;

/// One Scene.scan call, checked.
struct ScanCall {
  std::string lidar;
  std::optional<std::string> trajectory;
  std::string trajectoryTimes;
  int sweeps = 1;
  std::optional<int64_t> startNs;
  app::ScanOptions options;  ///< faceProperties: the names in `fields` that are no point field
  std::optional<std::vector<std::string>> fields;
  int threads = 0;
};

/// Scene.scan's arguments as a ScanCall; Error naming the argument for a bad one.
ScanCall scanCallOf(const std::string& lidar, const std::optional<std::string>& trajectory,
                    const std::string& trajectoryTimes, int sweeps, std::optional<double> start,
                    const std::string& frame, const std::string& returns, int surfaces,
                    const std::optional<std::vector<std::string>>& fields, double sigma,
                    double dropout, uint64_t seed, int threads);

/// The sweeps of `call` traced through `scene` with the GIL released: name -> 1-D array (the
/// fields asked for, or every one), the sweeps' points one after the other, sharing the
/// cloud's memory.
nb::dict scanArrays(const Scene& scene, const ScanCall& call);

}  // namespace aperture::python
