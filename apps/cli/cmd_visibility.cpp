// `aperture visibility`: which faces of a mesh, and which 3D points, the images of a camera
// file see (core/queries/visibility.h holds the definitions; docs/visibility.md the outputs). The
// cameras and the image selection are those of `aperture batch --cameras PATH --image NAME`,
// in the order batch renders them: camera index k is the k-th of that order.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>

#include "apps/cli/commands.h"
#include "apps/cli/scene_flags.h"
#include "apps/services/camera_file_params.h"
#include "apps/services/outputs.h"
#include "apps/services/render_options.h"
#include "apps/services/scene_setup.h"
#include "apps/services/visibility_arrays.h"
#include "cameras/files/camera_file.h"
#include "cameras/files/points_file.h"
#include "cameras/models/calibrated.h"
#include "cameras/registry/registry.h"
#include "core/io/npz.h"
#include "core/io/ply_writer.h"
#include "core/queries/visibility.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture::app {

namespace {

struct VisibilityArgs {
  SceneOptions scene;
  std::string cameras, points;
  std::vector<std::string> images, outs;
  bool frontOnly = false, quiet = false;
  double tolerance = 0.01;
  int threads = 0;
};

/// The images of the camera file, each as resolved camera parameters and its name.
struct SelectedCameras {
  CameraFile file;
  std::vector<const CalibratedImage*> images;
  std::vector<CameraParams> params;
  std::vector<std::string> names;
};

SelectedCameras selectCameras(const VisibilityArgs& a) {
  SelectedCameras s;
  s.file = readCameraFile(a.cameras, CameraFileOptions{a.scene.gltfScene});
  s.images = selectImages(s.file, a.images, "--image");
  if (s.images.empty())
    throw Error(cat("--cameras: '", a.cameras, "' has no images: nothing to compute"));
  for (const CalibratedImage* im : s.images) {
    s.params.push_back(resolveCameraParams(imageParamSet(s.file, *im)));
    if (s.params.back().type == "calibrated")
      calibratedSensorOf(s.params.back());  // the lens is checked before the mesh loads
    s.names.push_back(im->name);
  }
  return s;
}

/// ".npz" or ".ply" (lower case) of an --out path that checkOutputPath accepted.
std::string visibilityExtension(const std::string& path) {
  return toLowerAscii(path.substr(path.size() - 4));
}

/// The flags, checked before any work: --out (repeatable: .npz and/or .ply, each at most
/// once), --points needing the .npz, the tolerance, --threads, --cull.
void checkVisibilityArgs(const VisibilityArgs& a) {
  if (a.outs.empty()) throw Error("--out: give OUT.npz and/or OUT.ply");
  std::map<std::string, std::string> byExtension;
  for (const std::string& out : a.outs) {
    checkOutputPath("--out", out, OutputKind::Visibility);
    const std::string ext = visibilityExtension(out);
    const auto [it, fresh] = byExtension.emplace(ext, out);
    if (!fresh)
      throw Error(cat("--out: '", out, "': a second ", ext, " output (also '", it->second, "')"));
  }
  if (!a.points.empty() && !byExtension.count(".npz"))
    throw Error(cat("--points: '", a.points,
                    "': point visibility is written to the .npz; add --out OUT.npz"));
  if (a.tolerance < 0 || !(a.tolerance < 1))
    throw Error(cat("--occlusion-tolerance ", a.tolerance, " must be in [0, 1)"));
  if (a.threads < 0 || a.threads > 4096)
    throw Error(cat("--threads ", a.threads, " must be in [0, 4096]"));
  if (a.scene.cull)
    throw Error("--cull: visibility counts every face of the mesh; it cannot leave faces out");
}

/// Progress on stderr after each camera: one updating line on a terminal, a line per tenth
/// otherwise, nothing with --quiet.
std::function<void(size_t, size_t)> progressLine(const char* what, bool quiet) {
  if (quiet) return {};
  const bool tty = isatty(fileno(stderr));
  return [what, tty](size_t done, size_t total) {
    if (tty) {
      std::fprintf(stderr, "\raperture: %s %zu/%zu cameras%s", what, done, total,
                   done == total ? "\n" : "");
    } else if (done == total || (done * 10 / total) != ((done - 1) * 10 / total)) {
      std::fprintf(stderr, "aperture: %s %zu/%zu cameras\n", what, done, total);
    }
  };
}

/// The track observations of a COLMAP points file, as (point, camera) pairs among the selected
/// images; `unselected` counts those in images not selected (or absent from the camera file).
std::vector<PointObservation> trackObservations(const PointsFile& points,
                                                const SelectedCameras& cams, uint64_t& unselected) {
  std::map<std::string, uint32_t> cameraOfImageId;
  for (size_t k = 0; k < cams.images.size(); ++k) {
    const size_t index = size_t(cams.images[k] - cams.file.images.data());
    if (index < cams.file.imageIds.size()) cameraOfImageId[cams.file.imageIds[index]] = uint32_t(k);
  }
  std::vector<PointObservation> out;
  unselected = 0;
  for (size_t p = 0; p + 1 < points.trackIndptr.size(); ++p)
    for (uint64_t t = points.trackIndptr[p]; t < points.trackIndptr[p + 1]; ++t) {
      const auto it = cameraOfImageId.find(std::to_string(points.trackImageIds[t]));
      if (it == cameraOfImageId.end())
        ++unselected;
      else
        out.push_back({uint32_t(p), it->second});
    }
  return out;
}

size_t countNonEmptyRows(const SparseRows& rows) {
  size_t n = 0;
  for (size_t r = 0; r < rows.rows(); ++r) n += rows.indptr[r + 1] > rows.indptr[r];
  return n;
}

void printFaceSummary(const FaceVisibility& v, size_t cameras, double seconds) {
  uint64_t pixels = 0;
  for (uint64_t p : v.pixels) pixels += p;
  std::printf(
      "faces: %zu, seen by at least one of %zu cameras: %zu (%.2f %%); face-camera pairs: "
      "%zu; pixels on the mesh: %llu; %.3f s\n",
      v.viewCount.size(), cameras, countNonEmptyRows(v.faceCameras),
      v.viewCount.empty()
          ? 0.0
          : 100.0 * double(countNonEmptyRows(v.faceCameras)) / double(v.viewCount.size()),
      v.cameraFaces.indices.size(), static_cast<unsigned long long>(pixels), seconds);
}

/// Writes the .npz and .ply outputs (each atomically).
void writeVisibilityOutputs(const VisibilityArgs& a, const LoadedScene& loaded,
                            const std::vector<std::string>& cameraNames,
                            const FaceVisibility& faces, const PointVisibility* points) {
  for (const std::string& out : a.outs) {
    if (visibilityExtension(out) == ".npz") {
      std::vector<uint8_t> nameBytes;
      std::vector<NpzArray> arrays = {npzStringArray("camera_names", cameraNames, nameBytes)};
      for (const NpzArray& x : faceVisibilityArrays(faces)) arrays.push_back(x);
      if (points)
        for (const NpzArray& x : pointVisibilityArrays(*points)) arrays.push_back(x);
      writeNpz(out, arrays);
    } else {
      writePlyWithFaceProperties(out, loaded.meshes.front(),
                                 {{"view_count", PlyType::UInt32, faces.viewCount.data()},
                                  {"best_view", PlyType::Int32,
                                   reinterpret_cast<const uint32_t*>(faces.bestView.data())}});
    }
    if (!a.quiet) std::fprintf(stderr, "aperture: wrote %s\n", out.c_str());
  }
}

/// Face visibility numbers the faces of one mesh placed once: the .npz's per-face arrays and
/// the .ply's faces are that mesh's triangles in its loaded order. A scene file that places
/// several meshes, or one mesh several times (a glTF of several mesh nodes), is refused before
/// its BVH is built, naming what it places; a glTF whose scene places one mesh works as a PLY.
void checkOneMeshPlacedOnce(const LoadedScene& loaded) {
  if (loaded.objects.size() == 1 && loaded.names.size() == 1) return;
  std::vector<std::string> instances;
  for (const SceneObject& o : loaded.objects)
    instances.push_back(o.ids.instance < loaded.ids.instance.size()
                            ? loaded.ids.instance[o.ids.instance]
                            : std::to_string(o.ids.instance));
  throw Error(cat("visibility: ", join(loaded.names, ", "), ": the scene places ",
                  loaded.objects.size(), " meshes (", join(instances, ", "),
                  "); face visibility numbers the faces of one mesh placed once, so give one "
                  "mesh file whose scene places one mesh (for a glTF: a scene of one mesh "
                  "node, --gltf-scene N)"));
}

int runVisibility(const VisibilityArgs& a) {
  // Everything that can be checked is checked before the mesh loads.
  checkVisibilityArgs(a);
  const SelectedCameras cams = selectCameras(a);
  std::optional<PointsFile> points;
  if (!a.points.empty()) points = readPointsFile(a.points);
  AovSet primIds = parseAovSet("primid");
  glm::ivec2 largest(0);
  for (const CameraParams& p : cams.params)
    if (int64_t(p.width) * p.height > int64_t(largest.x) * largest.y) largest = {p.width, p.height};
  checkMemoryBudget(a.scene, largest, primIds, 0, false, cams.params);

  ThreadLimit threads(a.threads);
  Device device;
  const SceneSpec spec = a.scene.spec();
  LoadedScene loaded = loadSceneMeshes(spec, a.quiet);
  checkOneMeshPlacedOnce(loaded);
  buildLoadedScene(device, loaded, spec, a.quiet);
  std::vector<std::unique_ptr<Camera>> owned;
  std::vector<const Camera*> cameras;
  for (const CameraParams& p : cams.params) {
    owned.push_back(makeCamera(p, loaded.scene->renderOrigin()));
    cameras.push_back(owned.back().get());
  }

  FaceVisibilityOptions faceOptions;
  faceOptions.frontOnly = a.frontOnly;
  faceOptions.progress = progressLine("face visibility", a.quiet);
  const auto start = std::chrono::steady_clock::now();
  const FaceVisibility faces = faceVisibility(*loaded.scene, cameras, faceOptions);
  printFaceSummary(faces, cameras.size(),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());

  std::optional<PointVisibility> pointsSeen;
  if (points) {
    PointVisibilityOptions pointOptions;
    pointOptions.tolerance = a.tolerance;
    pointOptions.progress = progressLine("point visibility", a.quiet);
    pointsSeen = pointVisibility(*loaded.scene, cameras, points->positions, pointOptions);
    std::printf("points: %zu (%s), seen by at least one camera: %zu; point-camera pairs: %zu\n",
                points->positions.size(), pointsFormatName(points->format),
                countNonEmptyRows(pointsSeen->pointCameras),
                pointsSeen->pointCameras.indices.size());
    if (points->hasTracks()) {
      uint64_t unselected = 0;
      const std::vector<PointObservation> obs = trackObservations(*points, cams, unselected);
      const ObservationCounts n =
          classifyObservations(*loaded.scene, cameras, points->positions, obs, a.tolerance);
      std::printf(
          "track observations: %zu in the selected images: %llu occluded by the mesh, "
          "%llu seen, %llu outside the image; %llu in other images\n",
          obs.size(), static_cast<unsigned long long>(n.occluded),
          static_cast<unsigned long long>(n.seen), static_cast<unsigned long long>(n.outside),
          static_cast<unsigned long long>(unselected));
    }
  }
  writeVisibilityOutputs(a, loaded, cams.names, faces, pointsSeen ? &*pointsSeen : nullptr);
  return 0;
}

}  // namespace

Command addVisibilityCommand(CLI::App& app) {
  auto args = std::make_shared<VisibilityArgs>();
  CLI::App* sub = app.add_subcommand(
      "visibility",
      "Which faces of the mesh (and which 3D points) each image of a camera file sees "
      "(docs/visibility.md)");
  addSceneOptions(*sub, args->scene);
  sub->add_option("--cameras", args->cameras, kCameraFileHelp)->required()->type_name("PATH");
  sub->add_option("--image", args->images,
                  "Only this image (repeatable; the camera index follows this order, as batch)")
      ->type_name("NAME");
  sub->add_option("--out", args->outs,
                  "OUT.npz (every array; numpy.load) and/or OUT.ply (the mesh with the face "
                  "properties view_count and best_view); repeatable, written atomically")
      ->required()
      ->type_name("PATH");
  sub->add_flag("--front-only", args->frontOnly,
                "Count a camera only on the side a face's counter-clockwise winding faces");
  sub->add_option("--points", args->points,
                  "3D points: a COLMAP points3D.txt/.bin (or its model folder), a PLY's vertices "
                  "or an .npy of shape (N, 3); adds point_cameras_indptr/indices to the .npz")
      ->type_name("P");
  sub->add_option("--occlusion-tolerance", args->tolerance,
                  "A point at distance d is occluded by a surface closer than d * (1 - TOL) on "
                  "the camera's ray to it (ETH3D and invsfm use 0.01)")
      ->capture_default_str()
      ->type_name("TOL");
  sub->add_option("--threads", args->threads, "Worker threads in [0, 4096] (0 = all cores)");
  sub->add_flag("--quiet", args->quiet, "No progress or log lines (the summary still prints)");
  return [args] { return runVisibility(*args); };
}

}  // namespace aperture::app
