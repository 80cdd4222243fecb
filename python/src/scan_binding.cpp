// aperture.Scene.scan: LiDAR sweeps (apps/services/scan.h) of the Scene's own scene, the GIL
// released while tracing. The points come back as a dict of NumPy arrays that share the
// cloud's memory (no copy).
#include "scan_binding.h"

#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <memory>
#include <optional>

#include "apps/services/scan.h"
#include "bindings.h"
#include "core/io/npz.h"
#include "core/util/error.h"
#include "named_arrays.h"

namespace aperture::python {

namespace {

/// The standard fields a scan fills and "sweep" (for `fields` checks and the face properties'
/// names).
bool isStandardField(const std::string& name) {
  return name == "sweep" || isStandardPointField(name);
}

/// The sweeps' clouds as one: every field concatenated, plus "sweep" (uint32).
PointCloud concatenated(const std::vector<app::ScanSweep>& sweeps) {
  PointCloud out;
  for (const app::ScanSweep& s : sweeps) out.size += s.cloud.size;
  out.startSeconds = sweeps.empty() ? 0 : sweeps.front().cloud.startSeconds;
  if (sweeps.empty()) return out;
  for (const PointField& f : sweeps.front().cloud.fields) {
    PointField& g = out.addField(f.name, f.type);
    size_t at = 0;
    for (const app::ScanSweep& s : sweeps) {
      const PointField& h = *s.cloud.find(f.name);
      std::copy(h.bytes.begin(), h.bytes.end(), g.bytes.begin() + std::ptrdiff_t(at));
      at += h.bytes.size();
    }
  }
  auto* sweep = out.add<uint32_t>("sweep", PointType::UInt32);
  size_t at = 0;
  for (size_t k = 0; k < sweeps.size(); ++k)
    for (size_t i = 0; i < sweeps[k].cloud.size; ++i) sweep[at++] = uint32_t(k);
  return out;
}

}  // namespace

ScanCall scanCallOf(const std::string& lidar, const std::optional<std::string>& trajectory,
                    const std::string& trajectoryTimes, int sweeps, std::optional<double> start,
                    const std::string& frame, const std::string& returns, int surfaces,
                    const std::optional<std::vector<std::string>>& fields, double sigma,
                    double dropout, uint64_t seed, int threads) {
  ScanCall call;
  call.lidar = lidar;
  call.trajectory = trajectory;
  call.trajectoryTimes = trajectoryTimes;
  if (sweeps < 1) throw Error(cat("Scene.scan: sweeps ", sweeps, " must be at least 1"));
  call.sweeps = sweeps;
  if (start) call.startNs = parseTimeNs(cat(*start), "Scene.scan: start");
  app::ScanOptions& o = call.options;
  o.frame = app::parseScanFrame(frame);
  o.returns = app::parseScanReturns(returns);
  o.maxSurfaces = o.returns == app::ScanReturns::First ? 1 : surfaces;
  app::checkSurfacesPerRay(o.maxSurfaces, "Scene.scan: surfaces");  // first: 1, else surfaces
  o.noise = {sigma, dropout, seed};
  applyRangeNoise(o.noise, 1.0, 0, 0);  // checks σ and the dropout
  call.fields = fields;
  if (fields) {
    // Only the fields asked for are computed.
    o.fields.everyField = false;
    o.fields.names = *fields;
    for (const std::string& name : *fields)
      if (!isStandardField(name) && std::find(o.faceProperties.begin(), o.faceProperties.end(),
                                              name) == o.faceProperties.end())
        o.faceProperties.push_back(name);
  }
  call.threads = threads;
  return call;
}

nb::dict scanArrays(const Scene& scene, const ScanCall& call) {
  std::shared_ptr<PointCloud> cloud;
  withoutGil(call.threads, [&] {
    const LidarSensor sensor = loadLidar(call.lidar);
    const Trajectory path =
        call.trajectory ? loadTrajectory(*call.trajectory, call.trajectoryTimes) : Trajectory();
    const int64_t period = sensor.periodNs();
    app::SweepScanner scanner(scene, sensor, call.options);
    std::vector<app::ScanSweep> results;
    for (int k = 0; k < call.sweeps; ++k) {
      const LidarRays rays = sweepRays(sensor, path, k, app::sweepStartNs(call.startNs, k, period));
      results.push_back(scanner.scan(rays));
    }
    cloud = std::make_shared<PointCloud>(concatenated(results));
  });
  std::vector<NpzArray> arrays;
  const std::vector<std::string> names = call.fields ? *call.fields : [&] {
    std::vector<std::string> all;
    for (const PointField& f : cloud->fields) all.push_back(f.name);
    return all;
  }();
  for (const std::string& name : names) {
    const PointField* f = cloud->find(name);
    if (!f) {
      std::vector<std::string> known;
      for (const PointField& g : cloud->fields) known.push_back(g.name);
      throw Error(cat("Scene.scan: no field '", name, "' (known: ", join(known, ", "), ")"));
    }
    arrays.push_back({f->name,
                      npyDescrOf(f->type),
                      {uint64_t(cloud->size)},
                      f->bytes.data(),
                      uint64_t(f->bytes.size())});
  }
  return namedArrays(cloud, arrays);
}

}  // namespace aperture::python
