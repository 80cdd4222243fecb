// aperture.Scene.scan: LiDAR sweeps (apps/services/scan.h) of a scene of its own, loaded with
// the face properties the scan carries, the GIL released for loading and tracing. The points
// come back as a dict of NumPy arrays that share the cloud's memory (no copy).
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <memory>
#include <optional>

#include "apps/services/render_options.h"
#include "apps/services/scan.h"
#include "bindings.h"
#include "core/io/npz.h"
#include "core/util/error.h"
#include "named_arrays.h"

namespace aperture::python {

namespace {

/// The standard fields a scan fills (for `fields` checks and the face properties' names).
bool isStandardField(const std::string& name) {
  namespace pf = point_fields;
  for (const char* f : {pf::kX, pf::kY, pf::kZ, pf::kRange, pf::kTime, pf::kRing, pf::kColumn,
                        pf::kAzimuth, pf::kIncidence, pf::kPrimId, pf::kGeomId, pf::kInstance,
                        pf::kIntensity, pf::kReturnNumber, pf::kReturns, "sweep"})
    if (name == f) return true;
  return false;
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

class PyScanScene {
 public:
  PyScanScene(const std::vector<std::string>& meshes, const std::vector<std::string>& properties,
              bool robust, const std::string& quality, bool compact, bool worldSpace)
      : device_(std::make_unique<Device>()) {
    app::SceneOptions o;
    o.meshes = meshes;
    o.robust = robust;
    o.quality = quality;
    o.compact = compact;
    o.worldSpace = worldSpace;
    options_.faceProperties = properties;
    nb::gil_scoped_release release;
    loaded_ = app::loadScene(*device_, app::scanSceneSpec(o, options_), true);
  }

  /// One mesh from world positions (n, 3) and triangles (m, 3), finished as a loaded file is.
  PyScanScene(const nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>& v,
              const nb::ndarray<const uint32_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>& f,
              bool robust, const std::string& quality, bool compact, bool worldSpace)
      : device_(std::make_unique<Device>()) {
    app::SceneOptions o;
    o.robust = robust;
    o.quality = quality;
    o.compact = compact;
    o.worldSpace = worldSpace;
    Mesh mesh;
    mesh.name = "arrays";
    mesh.vertexCount = v.shape(0);
    mesh.positionsDouble.assign(v.data(), v.data() + 3 * v.shape(0));
    mesh.indices.assign(f.data(), f.data() + 3 * f.shape(0));
    mesh.stats.sourceFaces = f.shape(0);
    nb::gil_scoped_release release;
    app::SceneSpec spec = o.spec();
    spec.meshes = {{mesh.name, std::nullopt}};
    loaded_ = app::loadedSceneOfMesh(std::move(mesh), o.loadOptions());
    app::buildLoadedScene(*device_, loaded_, spec, true);
  }

  nb::dict scan(const std::string& lidar, const std::optional<std::string>& trajectory,
                const std::string& trajectoryTimes, int sweeps, std::optional<double> start,
                const std::string& frame, const std::string& returns, int surfaces,
                const std::optional<std::vector<std::string>>& fields, double sigma, double dropout,
                uint64_t seed, int threads) {
    app::ScanOptions o = options_;
    o.frame = app::parseScanFrame(frame);
    o.returns = app::parseScanReturns(returns);
    o.maxSurfaces = o.returns == app::ScanReturns::First ? 1 : surfaces;
    o.noise = {sigma, dropout, seed};
    if (sweeps < 1) throw Error(cat("Scene.scan: sweeps ", sweeps, " must be at least 1"));
    std::vector<app::ScanSweep> results;
    std::shared_ptr<PointCloud> cloud;
    {
      nb::gil_scoped_release release;
      const app::ThreadLimit limit(threads);
      const LidarSensor sensor = loadLidar(lidar);
      const Trajectory path =
          trajectory ? loadTrajectory(*trajectory, trajectoryTimes) : Trajectory();
      const int64_t period = sensor.periodNs();
      std::optional<int64_t> startNs;
      if (start) startNs = parseTimeNs(cat(*start), "Scene.scan: start");
      for (int k = 0; k < sweeps; ++k) {
        const LidarRays rays = sweepRays(
            sensor, path, k,
            startNs ? std::optional<int64_t>(*startNs + int64_t(k) * period) : std::nullopt);
        results.push_back(app::scanSweep(*loaded_.scene, sensor, rays, o));
      }
      cloud = std::make_shared<PointCloud>(concatenated(results));
    }
    std::vector<NpzArray> arrays;
    const std::vector<std::string> names = fields ? *fields : [&] {
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

 private:
  std::unique_ptr<Device> device_;
  app::ScanOptions options_;
  app::LoadedScene loaded_;
};

}  // namespace

void bindScan(nb::module_& m) {
  nb::class_<PyScanScene>(m, "_ScanScene", "The scene Scene.scan traces (face properties loaded)")
      .def(nb::init<const std::vector<std::string>&, const std::vector<std::string>&, bool,
                    const std::string&, bool, bool>(),
           nb::arg("meshes"), nb::arg("properties"), nb::arg("robust"), nb::arg("quality"),
           nb::arg("compact"), nb::arg("world_space"))
      .def(nb::init<
               const nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>&,
               const nb::ndarray<const uint32_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>&,
               bool, const std::string&, bool, bool>(),
           nb::arg("vertices"), nb::arg("faces"), nb::arg("robust"), nb::arg("quality"),
           nb::arg("compact"), nb::arg("world_space"))
      .def("scan", &PyScanScene::scan, nb::arg("lidar"), nb::arg("trajectory").none(),
           nb::arg("trajectory_times"), nb::arg("sweeps"), nb::arg("start").none(),
           nb::arg("frame"), nb::arg("returns"), nb::arg("surfaces"), nb::arg("fields").none(),
           nb::arg("noise_sigma"), nb::arg("dropout"), nb::arg("seed"), nb::arg("threads"));
  m.def("_is_standard_scan_field", &isStandardField);
}

}  // namespace aperture::python
