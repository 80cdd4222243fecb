// `aperture query`: closest points, distances, signed distances and occupancy of 3D points
// against a mesh (apps/queries/point_queries.h; docs/queries.md holds the definitions and the
// arrays of the .npz).
#include <chrono>
#include <cstdio>
#include <memory>

#include "apps/cli/commands.h"
#include "apps/cli/scene_flags.h"
#include "apps/queries/point_queries.h"
#include "apps/services/outputs.h"
#include "apps/services/render_options.h"
#include "apps/services/scene_setup.h"
#include "cameras/files/points_file.h"
#include "core/io/npz.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

struct QueryArgs {
  SceneOptions scene;
  std::string points, what = "closest,distance", out, method = "automatic";
  int parityDirections = 1;
  int threads = 0;
  bool quiet = false;
};

/// The flags, checked before anything loads.
PointQueryRequest checkedRequest(const QueryArgs& a) {
  PointQueryRequest r = parsePointQueries(a.what, "--what");
  r.inside.method = parseInsideMethod(a.method);
  checkParityDirections(a.parityDirections, "--parity-directions");
  r.inside.parityDirections = a.parityDirections;
  checkOutputPath("--out", a.out, OutputKind::Query);
  if (a.threads < 0 || a.threads > 4096)
    throw Error(cat("--threads ", a.threads, " must be in [0, 4096]"));
  if (a.scene.cull)
    throw Error("--cull: a query needs every face of the mesh; it cannot leave faces out");
  return r;
}

/// The flat (x, y, z) coordinates of `file`'s points.
std::vector<double> coordinatesOf(const PointsFile& file) {
  std::vector<double> out;
  out.reserve(3 * file.positions.size());
  for (const glm::dvec3& p : file.positions) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}

void writeQueryOutput(const QueryArgs& a, const PointQueryRequest& request,
                      const PointQueryResults& r) {
  std::vector<NpzArray> arrays = pointQueryArrays(r, request);
  std::vector<uint8_t> methodBytes;
  if (request.needsInside()) {
    // A 0-d string array: numpy.load(...)["sign_method"] prints as the name.
    NpzArray method = npzStringArray("sign_method", {insideMethodOf(r)}, methodBytes);
    method.shape.clear();
    arrays.push_back(method);
  }
  writeNpz(a.out, arrays);
  if (!a.quiet) std::fprintf(stderr, "aperture: wrote %s\n", a.out.c_str());
}

int runQuery(const QueryArgs& a) {
  const PointQueryRequest request = checkedRequest(a);
  const PointsFile file = readPointsFile(a.points);
  const std::vector<double> points = coordinatesOf(file);
  ThreadLimit threads(a.threads);
  Device device;
  SceneSpec spec = a.scene.spec();
  // The scene is only queried: built with the context filter, parity traces each ray once
  // (core/queries/inside.h) instead of once per crossing.
  spec.build.contextFilter =
      spec.build.contextFilter ||
      (request.needsInside() && request.inside.method != InsideMethod::Winding);
  const LoadedScene loaded = loadScene(device, spec, a.quiet);
  const auto start = std::chrono::steady_clock::now();
  const PointQueryResults r =
      runPointQueries(*loaded.scene, points.data(), file.positions.size(), request);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("points: %zu (%s); %s%s%s in %.3f s (%.3g points/s)\n", r.count,
              pointsFormatName(file.format), a.what.c_str(),
              request.needsInside() ? ", inside by " : "",
              request.needsInside() ? insideMethodOf(r).c_str() : "", seconds,
              seconds > 0 ? double(r.count) / seconds : 0.0);
  if (r.nonFinite)
    std::fprintf(stderr, "aperture: warning: %zu points could not be queried (NaN results)\n",
                 r.nonFinite);
  writeQueryOutput(a, request, r);
  return 0;
}

}  // namespace

Command addQueryCommand(CLI::App& app) {
  auto args = std::make_shared<QueryArgs>();
  CLI::App* sub = app.add_subcommand(
      "query",
      "Closest points, distances, signed distances and occupancy of 3D points against the mesh "
      "(docs/queries.md)");
  addSceneOptions(*sub, args->scene);
  sub->add_option("--points", args->points,
                  "The query points: an .npy of shape (N, 3) (float32 or float64), a PLY's "
                  "vertices, or a COLMAP points3D.txt/.bin")
      ->required()
      ->type_name("P");
  sub->add_option("--what", args->what,
                  "Comma-separated: closest (points, primid, barycentric, geomid, instance), "
                  "distance, sign (signed_distance, negative inside), occupancy (1 inside)")
      ->capture_default_str()
      ->type_name("LIST");
  sub->add_option("--sign-method", args->method,
                  "How sign and occupancy decide inside: parity (crossings along a ray), "
                  "winding (generalized winding number), automatic (parity when the mesh is "
                  "closed, else winding); the method that ran is stored as sign_method")
      ->capture_default_str()
      ->type_name("METHOD");
  sub->add_option("--parity-directions", args->parityDirections,
                  "Parity: the majority over this many fixed ray directions (odd)")
      ->capture_default_str()
      ->type_name("K");
  sub->add_option("--out", args->out, "OUT.npz (numpy.load), written atomically")
      ->required()
      ->type_name("PATH");
  sub->add_option("--threads", args->threads, "Worker threads in [0, 4096] (0 = all cores)");
  sub->add_flag("--quiet", args->quiet, "No log lines (the summary still prints)");
  return [args] { return runQuery(*args); };
}

}  // namespace aperture::app
