#include "apps/options.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "cameras/culling.h"
#include "core/error.h"
#include "core/limits.h"

namespace aperture::app {

namespace {

std::vector<double> parseNumbers(const std::string& flag, const std::string& text, size_t n,
                                 const char* shape) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    size_t used = 0;
    double x = 0;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size())
      throw Error(
          cat(flag, ": '", item, "' in '", text, "' is not a number (expected ", shape, ")"));
    v.push_back(x);
  }
  if (v.size() != n)
    throw Error(
        cat(flag, ": expected ", shape, " (", n, " comma-separated numbers), got '", text, "'"));
  for (double x : v)
    if (!std::isfinite(x)) throw Error(cat(flag, ": '", text, "' has a non-finite value"));
  return v;
}

}  // namespace

glm::dvec3 parseVec3(const std::string& flag, const std::string& text) {
  auto v = parseNumbers(flag, text, 3, "X,Y,Z");
  return {v[0], v[1], v[2]};
}

glm::dvec2 parseVec2(const std::string& flag, const std::string& text) {
  auto v = parseNumbers(flag, text, 2, "A,B");
  return {v[0], v[1]};
}

glm::ivec2 parseImageSize(const std::string& size) {
  const glm::dvec2 sz = parseVec2("--size", size);
  constexpr double kMaxSide = 65536, kMaxPixels = 1 << 28;
  if (sz.x < 1 || sz.y < 1 || sz.x != std::floor(sz.x) || sz.y != std::floor(sz.y) ||
      sz.x > kMaxSide || sz.y > kMaxSide || sz.x * sz.y > kMaxPixels)
    throw Error(cat("--size: '", size, "' must be two whole numbers in [1, 65536] with at most ",
                    kMaxPixels, " pixels"));
  return {int(sz.x), int(sz.y)};
}

void checkMemoryBudget(const SceneOptions& o, glm::ivec2 size, AovMask aovs,
                       uint64_t extraBytesPerPixel) {
  const uint64_t limit = parseMemoryLimit("--max-memory", o.maxMemory);
  if (limit == 0) return;
  std::vector<std::string> specs = o.meshes;
  if (specs.empty()) specs.push_back("procedural:default");
  const MemoryEstimate e =
      estimateMemory(specs, uint64_t(size.x), uint64_t(size.y), aovs, extraBytesPerPixel);
  checkMemoryLimit(e, limit, "--max-memory", o.maxMemory);
}

LoadOptions SceneOptions::loadOptions() const {
  LoadOptions o;
  o.placement = worldSpace ? Placement::WorldSpace : Placement::CameraRelative;
  return o;
}

BuildOptions SceneOptions::buildOptions() const {
  BuildOptions b;
  b.quality = parseBvhQuality(quality);
  b.robust = robust;
  b.compact = compact;
  return b;
}

void addSceneOptions(CLI::App& app, SceneOptions& o) {
  app.add_option(
      "--mesh", o.meshes,
      "Mesh file (.ply, .obj) or procedural:NAME?k=v (e.g. procedural:spheres?tris=2000000);"
      " repeatable. Default: the procedural default scene");
  app.add_option("--bvh-quality", o.quality, "Embree BVH build quality: low, medium, high")
      ->capture_default_str();
  app.add_flag("--robust", o.robust, "Embree robust (watertight) traversal");
  app.add_flag("--compact", o.compact, "Embree compact BVH (less memory, slower)");
  app.add_flag("--cull", o.cull,
               "Build the BVH over only the triangles the camera's view volume may reach "
               "(conservative: the image is bit-identical; panoramas keep all)");
  app.add_option("--max-memory", o.maxMemory,
                 "Refuse the job before loading when its estimated memory (mesh buffers from "
                 "the file headers, ~80 bytes/triangle of BVH, framebuffers) exceeds BYTES "
                 "(suffix K, M, G, T) or, with 'auto', MemAvailable");
  app.add_flag("--world-space", o.worldSpace,
               "Store vertices as float32 world coordinates instead of relative to the mesh's "
               "bounding-box centre (camera-relative, the default); for measuring the difference");
}

void addCameraOptions(CLI::App& app, CameraOptions& o) {
  app.add_option("--camera", o.type,
                 "Camera model: perspective, orthographic, oblique, thinlens, equirect, fisheye")
      ->capture_default_str();
  app.add_option("--eye", o.eye, "Eye position X,Y,Z (default: frames the scene)");
  app.add_option("--at", o.at, "Look-at point X,Y,Z")
      ->excludes(app.add_option("--dir", o.dir, "View direction X,Y,Z"));
  app.add_option("--up", o.up, "Up vector X,Y,Z")->capture_default_str();
  app.add_option("--fov", o.fov, "Field of view in degrees, in (0, 180) (default 45, vertical)");
  app.add_option("--fov-axis", o.fovAxis, "Axis --fov spans: x, y or diagonal")
      ->capture_default_str();
  app.add_option("--d", o.d, "Image-plane distance d, scene units (with --viewport)");
  app.add_option("--viewport", o.viewport, "Viewport VW,VH on the image plane, scene units");
  app.add_option("--focal-length", o.focalLength, "35 mm-style focal length, millimetres");
  app.add_option("--sensor", o.sensor, "Sensor W_MM,H_MM for --focal-length (default 36,24)");
  app.add_option("--shift", o.shift, "Lens shift SX,SY in viewport units (0.5 = half a viewport)");
  app.add_flag("--architectural", o.architectural,
               "Keep the image plane vertical (parallel to up): verticals stay parallel");
  app.add_option("--oblique-dir", o.obliqueDir, "Oblique camera: common ray direction X,Y,Z");
  app.add_option("--oblique-angles", o.obliqueAngles,
                 "Oblique camera: shear angles AX,AY, degrees");
  app.add_option("--aperture", o.aperture, "Thin lens radius, scene units");
  app.add_option("--focus", o.focus, "Thin lens focus distance along the view axis, scene units");
  app.add_option("--lon", o.lon, "Equirect longitude range MIN,MAX, degrees (default -180,180)");
  app.add_option("--lat", o.lat, "Equirect latitude range MIN,MAX, degrees (default -90,90)");
  app.add_option("--fisheye-fov", o.fisheyeFov, "Fisheye field of view, degrees, up to 360")
      ->capture_default_str();
  app.add_option("--size", o.size,
                 "Image size W,H in pixels: each side in [1, 65536], "
                 "at most 2^28 pixels")
      ->capture_default_str();
  app.add_option("--spp", o.spp, "Samples per pixel in [1, 65536] (stratified; 1 = pixel centres)")
      ->capture_default_str();
}

void addRenderOptions(CLI::App& app, RenderOptions& o) {
  app.add_option("--aov", o.aovs,
                 "AOVs to compute: color, depth, distance, normal, position, primid, geomid, all")
      ->capture_default_str();
  app.add_option("--packet", o.packet, "Rays per Embree call: 1, 4, 8 or 16")
      ->capture_default_str();
  app.add_option("--tile", o.tile, "Tile size in pixels: a multiple of 4 in [4, 4096]")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "Worker threads in [0, 4096] (0 = all cores)")
      ->capture_default_str();
}

RenderSettings RenderOptions::settings(int spp) const {
  RenderSettings s;
  s.packetWidth = packet;
  s.tileSize = tile;
  s.spp = spp;
  validateRenderSettings(s);
  if (threads < 0 || threads > 4096)
    throw Error(cat("--threads ", threads, " must be in [0, 4096]"));
  return s;
}

CameraParams CameraOptions::toParams(const glm::dvec3& worldLo, const glm::dvec3& worldHi) const {
  CameraParams p;
  p.type = type;
  const glm::ivec2 sz = parseImageSize(size);
  p.width = sz.x;
  p.height = sz.y;
  if (spp < 1 || spp > 65536) throw Error(cat("--spp ", spp, " must be in [1, 65536]"));
  p.spp = spp;
  p.up = parseVec3("--up", up);
  if (fov != 0) p.fovDeg = fov;
  if (fovAxis == "x")
    p.fovAxis = FovAxis::X;
  else if (fovAxis == "y")
    p.fovAxis = FovAxis::Y;
  else if (fovAxis == "diagonal")
    p.fovAxis = FovAxis::Diagonal;
  else
    throw Error(cat("--fov-axis: '", fovAxis, "' is not one of x, y, diagonal"));
  if (d != 0) p.d = d;
  if (!viewport.empty()) p.viewport = parseVec2("--viewport", viewport);
  if (focalLength != 0) p.focalLengthMm = focalLength;
  if (!sensor.empty()) p.sensorMm = parseVec2("--sensor", sensor);
  if (!shift.empty()) p.shift = parseVec2("--shift", shift);
  p.architectural = architectural;
  if (!obliqueDir.empty()) p.obliqueDir = parseVec3("--oblique-dir", obliqueDir);
  if (!obliqueAngles.empty()) p.obliqueAnglesDeg = parseVec2("--oblique-angles", obliqueAngles);
  p.apertureRadius = aperture;
  if (focus != 0) p.focusDistance = focus;
  if (!lon.empty()) p.longitudeRangeDeg = parseVec2("--lon", lon);
  if (!lat.empty()) p.latitudeRangeDeg = parseVec2("--lat", lat);
  p.fisheyeFovDeg = fisheyeFov;

  const glm::dvec3 centre = 0.5 * (worldLo + worldHi);
  if (!at.empty()) p.at = parseVec3("--at", at);
  if (!dir.empty()) p.dir = parseVec3("--dir", dir);
  if (!eye.empty()) {
    p.eye = parseVec3("--eye", eye);
    if (!p.at && !p.dir) p.at = centre;
  } else {
    // Frame the scene: look at its centre from above-front, far enough for the bounding
    // sphere to fit the vertical field of view.
    const double radius = std::max(0.5 * glm::length(worldHi - worldLo), 1e-6);
    const double halfFov = 0.5 * p.fovDeg.value_or(45.0) * 3.14159265358979323846 / 180.0;
    const glm::dvec3 view =
        p.dir ? glm::normalize(*p.dir) : glm::normalize(glm::dvec3(-0.35, -0.45, -1.0));
    const glm::dvec3 target = p.at.value_or(centre);
    p.eye = target - view * (0.8 * radius / std::sin(halfFov));
    if (!p.dir) p.at = target;
  }
  if (p.d && !p.viewport) throw Error("--d needs --viewport (the viewport at that distance)");
  if (p.viewport && !p.d) p.d = 1.0;
  if (!p.fovDeg && !p.viewport && !p.focalLengthMm) p.fovDeg = 45.0;
  return p;
}

void logLoadedMesh(const Mesh& m) {
  std::fprintf(stderr, "aperture: loaded %s: %zu triangles, %zu vertices in %.3f s", m.name.c_str(),
               m.triangleCount(), m.vertexCount, m.stats.loadSeconds);
  if (m.stats.fileBytes)
    std::fprintf(stderr, " (%.1f MB/s)",
                 m.stats.fileBytes / 1e6 / std::max(m.stats.loadSeconds, 1e-9));
  std::fprintf(stderr, "\n");
  if (m.stats.nonFiniteVertices || m.stats.droppedTriangles)
    std::fprintf(stderr, "aperture: %s: %zu non-finite vertices, %zu triangles dropped\n",
                 m.name.c_str(), m.stats.nonFiniteVertices, m.stats.droppedTriangles);
}

std::vector<Mesh> loadMeshes(const SceneOptions& o, bool quiet) {
  std::vector<std::string> specs = o.meshes;
  if (specs.empty()) specs.push_back("procedural:default");
  std::vector<Mesh> meshes;
  for (const std::string& spec : specs) {
    meshes.push_back(loadMesh(spec, o.loadOptions()));
    if (!quiet) logLoadedMesh(meshes.back());
  }
  // Meshes share the first one's anchor (moved in double) so they share one render space.
  for (size_t k = 1; k < meshes.size(); ++k) moveAnchor(meshes[k], meshes[0].anchor);
  return meshes;
}

void moveAnchor(Mesh& m, const glm::dvec3& anchor) {
  const glm::dvec3 delta = m.anchor - anchor;
  for (size_t v = 0; v < m.vertexCount; ++v)
    for (int c = 0; c < 3; ++c)
      m.positions[3 * v + c] = float(double(m.positions[3 * v + c]) + delta[c]);
  m.anchor = anchor;
}

LoadedScene loadSceneMeshes(const SceneOptions& o, bool quiet) {
  LoadedScene s;
  const auto start = std::chrono::steady_clock::now();
  s.meshes = loadMeshes(o, quiet);
  s.loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const Mesh& m : s.meshes) {
    s.objects.push_back({&m, glm::dmat4(1.0), nullptr});
    s.fileBytes += m.stats.fileBytes;
    glm::vec3 a, b;
    m.bounds(a, b);
    lo = glm::min(lo, a);
    hi = glm::max(hi, b);
  }
  if (!(lo.x <= hi.x)) lo = hi = glm::vec3(0.0f);
  s.worldLo = s.meshes[0].anchor + glm::dvec3(lo);
  s.worldHi = s.meshes[0].anchor + glm::dvec3(hi);
  return s;
}

void logCullStats(const CullStats& c, size_t cameras) {
  std::fprintf(
      stderr,
      "aperture: culled to the view volume%s of %zu camera%s: kept %zu of %zu "
      "triangles (%.2f%%) in %.3f s\n",
      cameras == 1 ? "" : "s", cameras, cameras == 1 ? "" : "s", c.trianglesKept, c.trianglesBefore,
      c.trianglesBefore ? 100.0 * double(c.trianglesKept) / double(c.trianglesBefore) : 100.0,
      c.seconds);
}

void buildLoadedScene(const Device& device, LoadedScene& s, const SceneOptions& o, bool quiet,
                      const std::vector<CameraParams>& cameras) {
  if (o.cull) {
    if (cameras.empty()) throw Error("--cull: no camera is known to cull for");
    // Untransformed meshes sharing the first anchor: the render origin is that anchor.
    const CameraCuller culler = cullerFor(cameras, s.meshes[0].anchor);
    if (culler.seesEverything) {
      if (!quiet)
        std::fprintf(stderr,
                     "aperture: --cull: a panorama camera sees all space; nothing culled\n");
    } else {
      s.cull = cullObjects(s.objects, culler.test(), s.subsets);
      if (!quiet) logCullStats(*s.cull, cameras.size());
    }
  }
  s.scene = std::make_unique<Scene>(device, s.objects, o.buildOptions());
  if (!quiet) {
    const BuildStats& b = s.scene->stats();
    std::fprintf(stderr,
                 "aperture: built BVH (%s%s%s): %zu triangles in %.3f s, Embree memory %.1f MB "
                 "(%.1f bytes/triangle)\n",
                 bvhQualityName(o.buildOptions().quality), o.robust ? ", robust" : "",
                 o.compact ? ", compact" : "", b.triangles, b.buildSeconds, b.embreeBytes / 1e6,
                 b.triangles ? double(b.embreeBytes) / double(b.triangles) : 0.0);
  }
}

LoadedScene loadScene(const Device& device, const SceneOptions& o, bool quiet) {
  LoadedScene s = loadSceneMeshes(o, quiet);
  buildLoadedScene(device, s, o, quiet);
  return s;
}

namespace {
// Justified in bench/TRADEOFF.md (bunny, crown with its thin lens, bathroom):
//  fast: a medium BVH builds 3-35x faster than high and traces within 2 %; half color and no
//        EXR compression cut the write from 22-57 ms to 6-13 ms a frame (geometry stays float).
//  balanced: high + robust removes every primID mismatch at <= 8 % trace cost; 4 spp buys
//        5.5-6.4 dB of color PSNR for 3.4-5x the frame time.
//  exact: the study's reference itself: high, robust, 256 spp, float color, lossless zip.
const Preset kPresets[] = {
    {"fast", "medium", false, 1, true, "none"},
    {"balanced", "high", true, 4, false, "zip"},
    {"exact", "high", true, 256, false, "zip"},
};
}  // namespace

const Preset& findPreset(const std::string& name) {
  for (const Preset& p : kPresets)
    if (name == p.name) return p;
  throw Error(cat("--preset: unknown preset '", name, "' (known: fast, balanced, exact)"));
}

void addPresetOption(CLI::App& app, std::string& preset) {
  app.add_option("--preset", preset,
                 "fast (medium BVH, 1 spp, half color, no EXR compression), balanced (high robust "
                 "BVH, 4 spp, zip) or exact (high robust BVH, 256 spp, float, zip); flags given "
                 "explicitly win; measured in bench/TRADEOFF.md");
}

void applyPreset(const std::string& name, const CLI::App& sub, SceneOptions& scene,
                 CameraOptions& camera, bool* halfColor, std::string* compression) {
  if (name.empty()) return;
  const Preset& p = findPreset(name);
  if (sub.count("--bvh-quality") == 0) scene.quality = p.bvhQuality;
  if (sub.count("--robust") == 0) scene.robust = p.robust;
  if (sub.count("--spp") == 0) camera.spp = p.spp;
  if (halfColor && sub.count("--half") == 0) *halfColor = p.halfColor;
  if (compression && sub.count("--compression") == 0) *compression = p.compression;
}

struct ThreadLimitImpl {
  std::unique_ptr<tbb::global_control> control;
};

ThreadLimit::ThreadLimit(int n) : impl_(std::make_unique<ThreadLimitImpl>()) {
  if (n > 0)
    impl_->control = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, size_t(n));
  threads_ = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

ThreadLimit::~ThreadLimit() = default;

}  // namespace aperture::app
