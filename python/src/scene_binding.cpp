// aperture.Scene: meshes through the apps' one scene set-up (apps/services/scene_setup.h) or NumPy
// arrays through finishMesh, Scene.render over renderImages (core/engine/render.h), the face and
// point visibility (core/queries/visibility.h) and LiDAR scans (scan_binding.h), with the GIL
// released for the whole computation.
#include <nanobind/ndarray.h>
#include <nanobind/stl/function.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <memory>
#include <optional>

#include "apps/services/render_options.h"
#include "apps/services/scene_setup.h"
#include "apps/services/visibility_arrays.h"
#include "bindings.h"
#include "cameras/registry/registry.h"
#include "core/engine/layers.h"
#include "core/engine/render.h"
#include "core/queries/visibility.h"
#include "core/util/error.h"
#include "file_errors.h"
#include "named_arrays.h"
#include "query_binding.h"
#include "render_storage.h"
#include "scan_binding.h"

namespace aperture::python {

namespace {

/// The scene flags of the command line (--bvh-quality, --no-robust, --compact, --world-space,
/// --bvh-chunk, checked here under its Python name).
app::SceneOptions sceneOptions(bool robust, const std::string& quality, bool compact,
                               bool worldSpace, long long bvhChunk) {
  app::SceneOptions o;
  o.robust = robust;
  o.quality = quality;
  o.compact = compact;
  o.worldSpace = worldSpace;
  o.bvhChunk = (long long)checkedBvhChunkTriangles(bvhChunk, "Scene: bvh_chunk");
  return o;
}

/// What Scene.render measured last: the call's wall time and the rays of every frame.
struct RenderTotals {
  double seconds = 0;
  uint64_t rays = 0, hits = 0;
  size_t frames = 0;
};

/// Thrown on a render thread to stop the frame loop once the progress callback raised.
struct ProgressRaised {};

/// What a scene holds beyond positions (SceneSpec's mesh data and BVH flags): a scene made
/// for some AOVs is reloaded or rebuilt once when a render asks for more.
bool holdsEverything(const app::SceneSpec& have, const app::SceneSpec& need) {
  for (const PropertyAov& p : need.properties)
    if (std::find(have.properties.begin(), have.properties.end(), p) == have.properties.end())
      return false;
  const auto holds = [](bool h, bool n) { return h || !n; };
  return holds(have.vertexNormals, need.vertexNormals) && holds(have.texcoords, need.texcoords) &&
         holds(have.vertexColors, need.vertexColors) && holds(have.materials, need.materials) &&
         holds(have.groups, need.groups) && holds(have.textures, need.textures) &&
         holds(have.build.contextFilter, need.build.contextFilter);
}

/// `have` grown by what `need` adds (properties, vertex normals, the context filter).
app::SceneSpec unionOf(app::SceneSpec have, const app::SceneSpec& need) {
  for (const PropertyAov& p : need.properties)
    if (std::find(have.properties.begin(), have.properties.end(), p) == have.properties.end())
      have.properties.push_back(p);
  have.vertexNormals = have.vertexNormals || need.vertexNormals;
  have.texcoords = have.texcoords || need.texcoords;
  have.vertexColors = have.vertexColors || need.vertexColors;
  have.materials = have.materials || need.materials;
  have.groups = have.groups || need.groups;
  have.textures = have.textures || need.textures;
  have.build.contextFilter = have.build.contextFilter || need.build.contextFilter;
  return have;
}

class PyScene {
 public:
  /// Meshes by path or procedural spec, as `--mesh` takes them; `aovs`: what renders will ask
  /// for (the mesh data loaded up front; more is loaded on the first render that needs it).
  PyScene(const std::vector<std::string>& meshes, const app::SceneOptions& o, const AovSet& aovs)
      : device_(std::make_unique<Device>()), fromFiles_(true) {
    app::SceneOptions options = o;
    options.meshes = meshes;
    options.aovs = aovs;
    spec_ = options.spec();
    for (const std::string& m : meshes)
      if (m.rfind("procedural:", 0) != 0) files_.push_back(m);
    load();
  }

  /// One mesh from positions (world space, float or double, as a PLY's float or double
  /// properties load) and triangle indices; finished exactly as a loaded file is.
  PyScene(Mesh mesh, const app::SceneOptions& o) : device_(std::make_unique<Device>()) {
    spec_ = o.spec();
    spec_.meshes = {{mesh.name, std::nullopt}};
    loaded_ = app::loadedSceneOfMesh(std::move(mesh), o.loadOptions());
    app::buildLoadedScene(*device_, loaded_, spec_, true);
  }

  nb::object render(nb::handle cameras, const std::string& aovList, std::optional<int> spp,
                    int layers, const std::string& normalFrame, int threads,
                    const nb::object& progress, int packet, int tile, nb::handle out) {
    const bool single = nb::isinstance<PyCamera>(cameras);
    std::vector<CameraParams> params = cameraParamsOf(cameras, "Scene.render");
    // Everything is checked before any work, as the command line does.
    AovSet aovs = parseAovSet(aovList);
    if (layers != 0) checkLayerCount(layers, "layers");
    aovs.layers = layers;
    app::RenderOptions options;
    options.packet = packet;
    options.tile = tile;
    options.threads = threads;
    RenderSettings settings = options.settings(1);
    settings.normalFrame = parseNormalFrame(normalFrame);
    if (spp)
      for (CameraParams& p : params) p.spp = *spp;
    const std::vector<std::unique_ptr<Camera>> owned = camerasOf(params);
    const std::vector<const Camera*> frameCameras = pointersOf(owned);
    provide(aovs);

    // The progress callback runs with the GIL taken back; an exception it raises stops the
    // frame loop and is raised again here.
    std::exception_ptr raised;
    const size_t total = params.size();
    std::function<void(size_t)> onFrame;
    if (!progress.is_none())
      onFrame = [&](size_t done) {
        {
          nb::gil_scoped_acquire gil;
          try {
            progress(done, total);
            return;
          } catch (nb::python_error&) {
            raised = std::current_exception();
          }
        }
        throw ProgressRaised{};
      };
    // Frames of one size go into one stacked image, so each AOV is one (N, H, W[, C]) block
    // handed to NumPy as it is (one camera: (H, W[, C])); frames of mixed sizes get an image
    // each. The storage is the caller's arrays (out=) or fresh and unwritten: the render
    // threads write every value, misses included (render_storage.h).
    const bool stacked = single || sameSize(params);
    if (!stacked && !out.is_none())
      throw nb::value_error("Scene.render: out= needs one camera or cameras of one size");
    const size_t frameAxis = single ? 0 : params.size();
    std::vector<RenderStorage> storage;
    if (stacked)
      storage.push_back(renderStorage(params[0].width,
                                      int(size_t(params[0].height) * params.size()), aovs,
                                      frameAxis, out, "Scene.render"));
    else
      for (const CameraParams& p : params)
        storage.push_back(renderStorage(p.width, p.height, aovs, 0, nb::none(), "Scene.render"));
    std::vector<FramePixels> frames;
    for (const RenderStorage& s : storage) frames.push_back(s.pixels);
    std::vector<RenderStats> stats;
    const auto start = std::chrono::steady_clock::now();
    withoutGil(threads, [&] {
      try {
        stats = stacked ? renderImagesStacked(*loaded_.scene, frameCameras, settings, frames[0],
                                              onFrame)
                        : renderImages(*loaded_.scene, frameCameras, settings, frames, onFrame);
      } catch (const ProgressRaised&) {
      }
    });
    if (raised) std::rethrow_exception(raised);
    last_ = RenderTotals{};
    last_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    last_.frames = stats.size();
    for (const RenderStats& st : stats) last_.rays += st.raysTraced, last_.hits += st.hits;
    if (stacked) return renderedArrays(storage[0], frameAxis);
    return perFrameLists(storage);
  }

  /// Scene.face_visibility: faceVisibility (core/queries/visibility.h) with the GIL released, as
  /// the arrays of the command's .npz (apps/services/visibility_arrays.h).
  nb::dict faceVisibility(nb::handle cameras, bool frontOnly, int threads,
                          const std::string& method) {
    FaceVisibilityOptions options;
    options.frontOnly = frontOnly;
    if (method == "needed-rays")
      options.rays = FaceRays::needed;
    else if (method == "all-rays")
      options.rays = FaceRays::all;
    else
      throw nb::value_error(
          cat("Scene.face_visibility: method '", method, "' is not 'needed-rays' or 'all-rays'")
              .c_str());
    const std::vector<std::unique_ptr<Camera>> owned =
        camerasOf(cameraParamsOf(cameras, "Scene.face_visibility"));
    auto result = std::make_shared<FaceVisibility>();
    withoutGil(threads, [&] {
      *result = aperture::faceVisibility(*loaded_.scene, pointersOf(owned), options);
    });
    return namedArrays(result, app::faceVisibilityArrays(*result));
  }

  /// Scene.point_visibility: pointVisibility (core/queries/visibility.h) of world points (N, 3)
  /// with the GIL released.
  nb::dict pointVisibility(
      const nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>& points,
      nb::handle cameras, double tolerance, int threads) {
    const std::vector<std::unique_ptr<Camera>> owned =
        camerasOf(cameraParamsOf(cameras, "Scene.point_visibility"));
    std::vector<glm::dvec3> world(points.shape(0));
    for (size_t k = 0; k < world.size(); ++k)
      world[k] = {points.data()[3 * k], points.data()[3 * k + 1], points.data()[3 * k + 2]};
    PointVisibilityOptions options;
    options.tolerance = tolerance;
    auto result = std::make_shared<PointVisibility>();
    withoutGil(threads, [&] {
      *result = aperture::pointVisibility(*loaded_.scene, pointersOf(owned), world, options);
    });
    return namedArrays(result, app::pointVisibilityArrays(*result));
  }

  /// Scene.scan: LiDAR sweeps through this scene, once it holds what the scan needs
  /// (app::withScanNeeds: the face properties named in `fields`, reflectance, the context
  /// filter of multi-returns), loaded as a render's mesh data is.
  nb::dict scan(const std::string& lidar, const std::optional<std::string>& trajectory,
                const std::string& trajectoryTimes, int sweeps, std::optional<double> start,
                const std::string& frame, const std::string& returns, int surfaces,
                const std::optional<std::vector<std::string>>& fields, double sigma, double dropout,
                uint64_t seed, int threads) {
    const ScanCall call = scanCallOf(lidar, trajectory, trajectoryTimes, sweeps, start, frame,
                                     returns, surfaces, fields, sigma, dropout, seed, threads);
    if (!fromFiles_ && !call.options.faceProperties.empty())
      throw Error(cat("Scene.scan: face property '", call.options.faceProperties[0],
                      "' asked for in fields, but a Scene of arrays has no face properties"));
    provide(app::withScanNeeds(spec_, call.options));
    return scanArrays(*loaded_.scene, call);
  }

  nb::dict lastRender() const {
    nb::dict d;
    d["seconds"] = last_.seconds;
    d["rays"] = last_.rays;
    d["hits"] = last_.hits;
    d["frames"] = last_.frames;
    d["mrays_per_second"] = last_.seconds > 0 ? double(last_.rays) / last_.seconds * 1e-6 : 0.0;
    return d;
  }

  nb::tuple bounds() const {
    const glm::dvec3 lo = loaded_.worldLo, hi = loaded_.worldHi;
    return nb::make_tuple(nb::make_tuple(lo.x, lo.y, lo.z), nb::make_tuple(hi.x, hi.y, hi.z));
  }
  size_t triangleCount() const {
    size_t n = 0;
    for (const SceneObject& o : loaded_.objects) n += o.mesh->triangleCount();
    return n;
  }
  const std::vector<std::string>& meshNames() const { return loaded_.names; }
  /// The built scene (the point and ray queries, query_binding.h).
  const Scene& scene() const { return *loaded_.scene; }
  /// The closedness check and winding tree of the sign queries, kept until the scene changes.
  app::KeptInsideAnswers& keptInsideAnswers() const { return keptInside_; }

  /// Scene.ids: the names behind the instance, mesh and material ids (SceneIds).
  nb::dict ids() const {
    nb::dict d;
    d["instance"] = nb::cast(loaded_.ids.instance);
    d["mesh"] = nb::cast(loaded_.ids.mesh);
    d["material"] = nb::cast(loaded_.ids.material);
    return d;
  }

  /// Scene.triangles: every object's triangles in world space, (T, 3, 3) float64, objects in
  /// scene order and each object's triangles in their loaded order (primID order: a mesh put
  /// in spatial order is read back through Mesh::sourceTriangle).
  nb::ndarray<nb::numpy, double, nb::shape<-1, 3, 3>> triangles() const {
    size_t total = 0;
    for (const SceneObject& o : loaded_.objects) total += o.mesh->triangleCount();
    auto* out = new std::vector<double>(9 * total);
    size_t base = 0;
    for (const SceneObject& o : loaded_.objects) {
      const Mesh& m = *o.mesh;
      const size_t n = m.triangleCount();
      std::vector<uint32_t> order(n);
      for (size_t t = 0; t < n; ++t) order[t] = uint32_t(t);
      std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        return m.sourceTriangle(a) < m.sourceTriangle(b);
      });
      for (size_t k = 0; k < n; ++k)
        for (int c = 0; c < 3; ++c) {
          const size_t v = m.indices[3 * size_t(order[k]) + size_t(c)];
          const glm::dvec3 local = m.anchor + glm::dvec3(m.positions[3 * v], m.positions[3 * v + 1],
                                                         m.positions[3 * v + 2]);
          const glm::dvec3 world = glm::dvec3(o.worldFromMesh * glm::dvec4(local, 1.0));
          for (int a = 0; a < 3; ++a) (*out)[9 * (base + k) + size_t(3 * c + a)] = world[a];
        }
      base += n;
    }
    nb::capsule owner(out, [](void* p) noexcept { delete static_cast<std::vector<double>*>(p); });
    return nb::ndarray<nb::numpy, double, nb::shape<-1, 3, 3>>(out->data(), {total, 3, 3}, owner);
  }

 private:
  void load() {
    readingFiles(files_, [&] { loaded_ = app::loadSceneMeshes(spec_, true); });
    app::buildLoadedScene(*device_, loaded_, spec_, true);
  }

  /// Makes the scene hold what `aovs` read (withAovNeeds): files are loaded again with the
  /// mesh data added, an array scene is rebuilt with the BVH flags added (its mesh has no
  /// properties or vertex normals to load: the render then names what is missing).
  void provide(const AovSet& aovs) { provide(app::withAovNeeds(spec_, aovs)); }

  /// Makes the scene hold what `need` asks for beyond spec_ (the same way).
  void provide(const app::SceneSpec& need) {
    if (holdsEverything(spec_, need)) return;
    spec_ = unionOf(spec_, need);
    nb::gil_scoped_release release;
    keptInside_.forget();
    if (fromFiles_) {
      loaded_.scene.reset();
      load();
    } else {
      app::buildLoadedScene(*device_, loaded_, spec_, true);
    }
  }

  /// The parameters of a Camera or a sequence of Camera; TypeError naming `what` otherwise.
  static std::vector<CameraParams> cameraParamsOf(nb::handle cameras, const char* what) {
    std::vector<CameraParams> params;
    if (nb::isinstance<PyCamera>(cameras)) {
      params.push_back(nb::cast<const PyCamera&>(cameras).params);
      return params;
    }
    for (nb::handle c : cameras) {
      if (!nb::isinstance<PyCamera>(c))
        throw nb::type_error(
            cat(what, ": cameras must be a Camera or a sequence of Camera").c_str());
      params.push_back(nb::cast<const PyCamera&>(c).params);
    }
    return params;
  }

  /// The cameras of `params` in this scene's render space.
  std::vector<std::unique_ptr<Camera>> camerasOf(const std::vector<CameraParams>& params) const {
    std::vector<std::unique_ptr<Camera>> owned;
    for (const CameraParams& p : params)
      owned.push_back(makeCamera(p, loaded_.scene->renderOrigin()));
    return owned;
  }

  static std::vector<const Camera*> pointersOf(const std::vector<std::unique_ptr<Camera>>& owned) {
    std::vector<const Camera*> out;
    for (const auto& c : owned) out.push_back(c.get());
    return out;
  }

  static bool sameSize(const std::vector<CameraParams>& params) {
    for (const CameraParams& p : params)
      if (p.width != params[0].width || p.height != params[0].height) return false;
    return true;
  }

  /// Frames of mixed sizes: name -> list of (H, W[, C]) arrays, one per frame, no copy.
  static nb::dict perFrameLists(const std::vector<RenderStorage>& frames) {
    nb::dict out;
    for (const PixelChannel& c : frames[0].pixels.channels) out[c.name.c_str()] = nb::list();
    for (const RenderStorage& f : frames) {
      nb::dict one = renderedArrays(f, 0);
      for (auto [name, array] : one) nb::cast<nb::list>(out[name]).append(array);
    }
    return out;
  }

  std::unique_ptr<Device> device_;  // declared first: destroyed after the scene
  bool fromFiles_ = false;
  std::vector<std::string> files_;  // the mesh files, for messages of readingFiles
  app::SceneSpec spec_;
  app::LoadedScene loaded_;
  mutable app::KeptInsideAnswers keptInside_;  ///< keptInsideAnswers()
  RenderTotals last_;
};

template <typename Real>
Mesh meshOfArrays(
    const nb::ndarray<const Real, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>& v,
    const nb::ndarray<const uint32_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>& f,
    const std::string& name) {
  Mesh m;
  m.name = name;
  m.vertexCount = v.shape(0);
  if constexpr (std::is_same_v<Real, float>)
    m.positions.assign(v.data(), v.data() + 3 * v.shape(0));
  else
    m.positionsDouble.assign(v.data(), v.data() + 3 * v.shape(0));
  m.indices.assign(f.data(), f.data() + 3 * f.shape(0));
  m.stats.sourceFaces = f.shape(0);
  return m;
}

template <typename Real>
void bindArrayConstructor(nb::class_<PyScene>& c) {
  c.def_static(
      "_from_arrays",
      [](const nb::ndarray<const Real, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>& vertices,
         const nb::ndarray<const uint32_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>& faces,
         const std::string& name, bool robust, const std::string& quality, bool compact,
         bool worldSpace, long long bvhChunk) {
        const app::SceneOptions options =
            sceneOptions(robust, quality, compact, worldSpace, bvhChunk);
        Mesh mesh = meshOfArrays<Real>(vertices, faces, name);
        return std::make_unique<PyScene>(std::move(mesh), options);
      },
      nb::arg("vertices"), nb::arg("faces"), nb::arg("name"), nb::arg("robust"), nb::arg("quality"),
      nb::arg("compact"), nb::arg("world_space"), nb::arg("bvh_chunk"));
}

}  // namespace

void bindScene(nb::module_& m) {
  m.attr("_BVH_CHUNK_DEFAULT") = kBvhChunkTriangles;  // Scene(bvh_chunk=...)'s default
  nb::class_<PyScene> scene(m, "_Scene", "The C++ scene behind aperture.Scene");
  scene.def_static(
      "_from_paths",
      [](const std::vector<std::string>& meshes, bool robust, const std::string& quality,
         bool compact, bool worldSpace, long long bvhChunk, const std::string& aovs,
         std::optional<int> gltfScene) {
        app::SceneOptions options = sceneOptions(robust, quality, compact, worldSpace, bvhChunk);
        options.gltfScene = gltfScene;
        return std::make_unique<PyScene>(meshes, options,
                                         aovs.empty() ? AovSet() : parseAovSet(aovs));
      },
      nb::arg("meshes"), nb::arg("robust"), nb::arg("quality"), nb::arg("compact"),
      nb::arg("world_space"), nb::arg("bvh_chunk"), nb::arg("aovs"),
      nb::arg("gltf_scene") = nb::none());
  bindArrayConstructor<float>(scene);
  bindArrayConstructor<double>(scene);
  scene
      .def("_render", &PyScene::render, nb::arg("cameras"), nb::arg("aovs"), nb::arg("spp"),
           nb::arg("layers"), nb::arg("normal_frame"), nb::arg("threads"),
           nb::arg("progress").none(), nb::arg("packet"), nb::arg("tile"),
           nb::arg("out").none() = nb::none())
      .def("_face_visibility", &PyScene::faceVisibility, nb::arg("cameras"), nb::arg("front_only"),
           nb::arg("threads"), nb::arg("method"))
      .def("_scan", &PyScene::scan, nb::arg("lidar"), nb::arg("trajectory").none(),
           nb::arg("trajectory_times"), nb::arg("sweeps"), nb::arg("start").none(),
           nb::arg("frame"), nb::arg("returns"), nb::arg("surfaces"), nb::arg("fields").none(),
           nb::arg("noise_sigma"), nb::arg("dropout"), nb::arg("seed"), nb::arg("threads"))
      .def("_point_visibility", &PyScene::pointVisibility, nb::arg("points"), nb::arg("cameras"),
           nb::arg("tolerance"), nb::arg("threads"))
      .def_prop_ro("last_render", &PyScene::lastRender,
                   "Seconds, rays, hits, frames and Mrays/s of the last render call")
      .def_prop_ro("bounds", &PyScene::bounds, "World bounds ((x, y, z) low, (x, y, z) high)")
      .def_prop_ro("triangle_count", &PyScene::triangleCount, "Triangles in the scene")
      .def_prop_ro("mesh_names", &PyScene::meshNames, "The meshes, as given")
      .def_prop_ro("ids", &PyScene::ids,
                   "The names behind the instance, mesh and material ids, each list indexed by "
                   "its id")
      .def("triangles", &PyScene::triangles,
           "Every object's triangles in world space, (T, 3, 3) float64, in scene order");
  bindSceneQueries(scene);
}

}  // namespace aperture::python
