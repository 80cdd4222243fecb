#include "core/engine/render.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <deque>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <type_traits>
#include <utility>

#include "core/aov/aov_table.h"
#include "core/engine/coverage_mask.h"
#include "core/engine/interleaved_row.h"
#include "core/engine/intersect_scene.h"
#include "core/engine/layers.h"
#include "core/engine/packet.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/spelling.h"
#include "core/util/vector_kernel.h"

namespace aperture {

NormalFrame parseNormalFrame(const std::string& name) {
  for (NormalFrame f : {NormalFrame::World, NormalFrame::OpenCV, NormalFrame::OpenGL})
    if (name == normalFrameName(f)) return f;
  throw Error(cat("unknown normal frame '", name, "'",
                  didYouMean(name, {"world", "opencv", "opengl"}),
                  " (known: world, opencv, opengl)"));
}

const char* normalFrameName(NormalFrame frame) {
  switch (frame) {
    case NormalFrame::OpenCV:
      return "opencv";
    case NormalFrame::OpenGL:
      return "opengl";
    default:
      return "world";
  }
}

glm::dmat3 normalFrameFromWorld(NormalFrame frame, const CameraDescription& camera) {
  // glm matrices are built from columns; the rows of the rotation are the frame's axes in
  // world space, so the matrix is the transpose of the one with those columns.
  switch (frame) {
    case NormalFrame::OpenCV:
      return glm::transpose(glm::dmat3(camera.u, -camera.v, -camera.w));
    case NormalFrame::OpenGL:
      return glm::transpose(glm::dmat3(camera.u, camera.v, camera.w));
    default:
      return glm::dmat3(1.0);
  }
}

void validateRenderSettings(const RenderSettings& s) {
  if (s.packetWidth != 1 && s.packetWidth != 4 && s.packetWidth != 8 && s.packetWidth != 16)
    throw Error(cat("packet width ", s.packetWidth, " is not one of 1, 4, 8, 16"));
  if (s.tileSize < 4 || s.tileSize > 4096 || s.tileSize % 4 != 0)
    throw Error(cat("tile size ", s.tileSize, " must be a multiple of 4 in [4, 4096]"));
}

namespace {

/// For each property of `aovs`, each object's values of that property. Throws Error, before
/// anything is rendered, naming the first object mesh that lacks one.
std::vector<std::vector<const uint32_t*>> propertyTables(const Scene& scene, const AovSet& aovs) {
  std::vector<std::vector<const uint32_t*>> tables;
  for (const PropertyAov& property : aovs.properties) {
    std::vector<const uint32_t*> perObject;
    for (size_t object = 0; object < scene.objectCount(); ++object) {
      const Mesh& mesh = scene.objectMesh(unsigned(object));
      const MeshProperty* p = mesh.property(property.domain, property.name);
      if (!p)
        throw Error(cat("AOV '", property.aovName(), "': mesh '", mesh.name, "' (object ", object,
                        ") has no such property; was it loaded with it ",
                        "(LoadOptions::properties)?"));
      perObject.push_back(p->values.data());
    }
    tables.push_back(std::move(perObject));
  }
  return tables;
}

/// The domain of each property of `aovs`, in order.
std::vector<PropertyDomain> domainsOf(const AovSet& aovs) {
  std::vector<PropertyDomain> out;
  for (const PropertyAov& p : aovs.properties) out.push_back(p.domain);
  return out;
}

/// The surface AOVs (instance, mesh, material, barycentric, uv, vertex-color, albedo).
constexpr AovMask kSurfaceAovs = kAovInstanceId | kAovMeshId | kAovMaterialId | kAovBarycentric |
                                 kAovUv | kAovVertexColor | kAovAlbedo;

/// Checks, before anything is rendered, that the scene holds what the surface AOVs of `aovs`
/// read, and returns the looks the albedo AOV reads (null without albedo). Throws Error when
/// uv is asked of a scene where no object's mesh has texture coordinates, vertex-color where
/// none has colours, and albedo without the scene's looks, with a material an unsupported
/// extension leaves unknown, with a material id beyond the looks' materials, or with a textured
/// material on a mesh without texture coordinates. Objects without texture coordinates or
/// colours where others have them read 0 and (1, 1, 1, 1).
const SurfaceLooks* surfaceLooksFor(const Scene& scene, const AovSet& aovs) {
  const auto anyMesh = [&](auto&& has) {
    for (size_t object = 0; object < scene.objectCount(); ++object)
      if (has(scene.objectMesh(unsigned(object)))) return true;
    return false;
  };
  if (aovs.has(kAovUv) && !anyMesh([](const Mesh& m) { return !m.texcoords.empty(); }))
    throw Error(
        "AOV 'uv': no mesh of the scene has texture coordinates (glTF TEXCOORD_0, OBJ vt; "
        "loaded only when asked: LoadOptions::texcoords)");
  if (aovs.has(kAovVertexColor) && !anyMesh([](const Mesh& m) { return !m.vertexColors.empty(); }))
    throw Error(
        "AOV 'vertex-color': no mesh of the scene has vertex colours (glTF COLOR_0; loaded only "
        "when asked: LoadOptions::vertexColors)");
  if (!aovs.has(kAovAlbedo)) return nullptr;
  const SurfaceLooks* looks = scene.looks();
  if (!looks)
    throw Error(
        "AOV 'albedo': the scene has no materials (a glTF or OBJ scene file gives them; "
        "Scene::setLooks)");
  const std::vector<Material>& materials = looks->materials;
  for (size_t m = 0; m < materials.size(); ++m) {
    if (!materials[m].unsupported.empty())
      throw Error(cat("AOV 'albedo': material '", materials[m].name, "' (", m,
                      ") needs the extension ", materials[m].unsupported,
                      ", which aperture does not support, so its base colour is unknown"));
    if (materials[m].baseColorTexture >= 0 && !looks->textures)
      throw Error(cat("AOV 'albedo': material '", materials[m].name, "' (", m,
                      ") has a texture, but the scene's looks have no texture sampler"));
  }
  // Each mesh once per material base: the materials its triangles use.
  std::vector<std::pair<const Mesh*, uint32_t>> seen;
  for (size_t object = 0; object < scene.objectCount(); ++object) {
    const Mesh& mesh = scene.objectMesh(unsigned(object));
    const uint32_t base = scene.objectIds(unsigned(object)).materialBase;
    if (std::find(seen.begin(), seen.end(), std::pair(&mesh, base)) != seen.end()) continue;
    seen.emplace_back(&mesh, base);
    std::vector<bool> used(materials.size(), false);
    const auto use = [&](uint32_t local) {
      const uint64_t id = uint64_t(base) + local;
      if (id >= materials.size())
        throw Error(cat("AOV 'albedo': mesh '", mesh.name, "' (object ", object, ") uses material ",
                        id, ", but the scene has ", materials.size(), " materials"));
      if (used[size_t(id)]) return;
      used[size_t(id)] = true;
      if (materials[size_t(id)].baseColorTexture >= 0 && mesh.texcoords.empty())
        throw Error(cat("AOV 'albedo': mesh '", mesh.name, "' (object ", object,
                        ") has no texture coordinates, but its material '",
                        materials[size_t(id)].name, "' (", id, ") has a texture"));
    };
    if (mesh.faceMaterials.empty()) use(0);
    for (uint32_t local : mesh.faceMaterials) use(local);
  }
  return looks;
}

/// The box the frame loop's scene-box test uses for `camera`: the scene's, or null when the
/// test is off (RenderSettings::sceneBoxTest), the scene has no box, or every ray of the
/// camera starts inside the box at tnear 0 (Camera::sharedRayOrigin), so none can miss it.
const SceneBox* boxTestFor(const Scene& scene, const Camera& camera, const RenderSettings& s) {
  if (!s.sceneBoxTest || !scene.box()) return nullptr;
  const std::optional<glm::vec3> origin = camera.sharedRayOrigin();
  if (origin && boxContains(*scene.box(), *origin)) return nullptr;
  return &*scene.box();
}

/// The coverage mask (core/engine/coverage_mask.h) of `camera` when RenderSettings::coverageMask
/// applies and the camera's rays start at one eye along a projective map, or along a lens's
/// pixel-centre directions (Camera::lensBlockBounds); it then replaces the box test.
std::optional<CoverageMask> coverageFor(const Scene& scene, const Camera& camera,
                                        const RenderSettings& s) {
  if (!s.sceneBoxTest || !s.coverageMask || !scene.box()) return std::nullopt;
  const std::optional<CentralProjection> projection =
      centralProjectionOf(camera, scene.renderOrigin());
  const std::optional<LensBlockBounds> lens = projection ? std::nullopt : camera.lensBlockBounds();
  const std::optional<glm::vec3> origin = camera.sharedRayOrigin();
  if (!projection && !(lens && origin)) return std::nullopt;
  const Occupancy* occupancy = scene.occupancy();
  if (!occupancy) return std::nullopt;
  if (projection) return refinedCoverageMask(*occupancy, *projection, s.spp);
  return lensCoverageMask(*occupancy, *lens, *origin);
}

struct ImagePlan;

/// A framebuffer channel the frame loop stores pixels into: its pixel 0 and the bytes of a
/// pixel.
struct WrittenChannel {
  const char* pixels;
  size_t bytesPerPixel;
};

/// The per-pixel channels of `px` the frame loop stores into: every AOV it holds (its one list
/// of channels), but the layered hits of more than one layer, whose pixels lie layer after
/// layer.
std::vector<WrittenChannel> writtenChannels(const FramePixels& px) {
  std::vector<WrittenChannel> out;
  for (const PixelChannel& c : px.channels)
    if (c.layers == 1)
      out.push_back({static_cast<const char*>(c.data), sizeof(uint32_t) * size_t(c.channels)});
  return out;
}

/// The first value of the fixed AOV `bit` in `px` as T (float or uint32_t), null when `px`
/// does not hold it.
template <class T>
T* fixedChannel(const FramePixels& px, Aov bit) {
  if (!px.aovs.has(bit)) return nullptr;
  for (const AovRow& row : aovTable())
    if (row.bit == AovMask(bit))
      if (const PixelChannel* c = px.find(row.name)) return static_cast<T*>(c->data);
  throw Error(cat("frame pixels: AOV bit ", uint32_t(bit), " has no storage"));
}

/// Where the frame loop stores each AOV: its first value in the plan's storage (null for the
/// AOVs not rendered).
struct AovStores {
  float *rgba, *depth, *distance, *normal, *position, *shadingNormal;
  float *barycentric, *uv, *vertexColor, *albedo;
  uint32_t *primId, *geomId, *instanceId, *meshId, *materialId;
  std::vector<uint32_t*> properties;  ///< in AovSet::properties order

  explicit AovStores(const FramePixels& px)
      : rgba(fixedChannel<float>(px, kAovColor)),
        depth(fixedChannel<float>(px, kAovDepth)),
        distance(fixedChannel<float>(px, kAovDistance)),
        normal(fixedChannel<float>(px, kAovNormal)),
        position(fixedChannel<float>(px, kAovPosition)),
        shadingNormal(fixedChannel<float>(px, kAovShadingNormal)),
        barycentric(fixedChannel<float>(px, kAovBarycentric)),
        uv(fixedChannel<float>(px, kAovUv)),
        vertexColor(fixedChannel<float>(px, kAovVertexColor)),
        albedo(fixedChannel<float>(px, kAovAlbedo)),
        primId(fixedChannel<uint32_t>(px, kAovPrimId)),
        geomId(fixedChannel<uint32_t>(px, kAovGeomId)),
        instanceId(fixedChannel<uint32_t>(px, kAovInstanceId)),
        meshId(fixedChannel<uint32_t>(px, kAovMeshId)),
        materialId(fixedChannel<uint32_t>(px, kAovMaterialId)) {
    for (const PropertyAov& p : px.aovs.properties)
      properties.push_back(static_cast<uint32_t*>(px.find(p.aovName())->data));
  }
};

/// A channel whose miss values the frame loop writes (FramePixels::missesWritten false): its
/// first value, values a pixel, layers and the stride between them (values), and the miss.
struct MissChannel {
  uint32_t* data;
  size_t channels, layers, layerStride;
  uint32_t bits;
};

std::vector<MissChannel> missChannels(const FramePixels& px) {
  std::vector<MissChannel> out;
  if (px.missesWritten) return out;
  for (const PixelChannel& c : px.channels)
    out.push_back({static_cast<uint32_t*>(c.data), size_t(c.channels), size_t(c.layers),
                   px.pixelCount() * size_t(c.channels), c.missBits});
  return out;
}

struct TileCounters {
  uint64_t traced = 0, skipped = 0, outsideBox = 0, hits = 0;
};

/// Renders the tile of columns [x0, x1) and rows [y0, y1) of a plan's frame.
using TileRenderer = void (*)(const ImagePlan& plan, int x0, int y0, int x1, int y1,
                              TileCounters& count);
/// The tile renderer for the settings' packet width and trace mode (Embree or null).
TileRenderer tileRendererFor(const RenderSettings& settings);

/// What one frame computes, decided once from the framebuffer's AOVs.
struct ImagePlan {
  /// `pixelOffset`: where the camera's pixel (0, 0) is in `px` (frame k of stacked frames
  /// starts at k·W·H; 0 otherwise).
  ImagePlan(const Scene& scene, const Camera& camera, const RenderSettings& settings,
            const FramePixels& px, size_t pixelOffset = 0);

  const Scene& scene;
  const Camera& camera;
  AovStores out;  // where each AOV's pixels go
  RenderSettings settings;
  CameraDescription description;  // the camera's, taken once
  int width, height;              // the camera's image
  size_t pixelOffset;             // storage index of the image's pixel (0, 0)
  glm::vec3 eye, axis;            // render space
  glm::dvec3 origin;              // world position of the render-space origin
  bool color, depth, distance, normal, position, primId, geomId;
  bool shadingNormal;
  bool instanceId, meshId, materialId, barycentric, uv, vertexColor, albedo;
  bool surface;               // any of the seven above (kSurfaceAovs)
  const SurfaceLooks* looks;  // the albedo AOV's materials and textures (surfaceLooksFor)
  bool rotateNormals;         // normalFrame is not World: normals go through frameFromWorld
  glm::mat3 frameFromWorld;   // normalFrameFromWorld(settings.normalFrame, camera)
  /// Per requested property (AovSet::properties order), per object: the mesh's values.
  std::vector<std::vector<const uint32_t*>> propertyValues;
  std::vector<PropertyDomain> propertyDomains;  // per requested property
  /// Anything of the mesh data pass (storeMeshDataLane): decided once, so a frame without
  /// it runs the geometry store unchanged.
  bool meshData;
  std::optional<LayerPlan> layers;  // --layers K: the first K surfaces of the centre ray
  bool anyGeometry;                 // any AOV filled from the centre ray
  bool instanced;                   // normals of instanced hits need the instance's normal matrix
  bool remapPrimIds;                // Scene::remapsPrimIds: culled or reordered, primID is mapped
  /// The blocks that may see the scene (coverageFor); packets outside are misses.
  std::optional<CoverageMask> coverage;
  /// Packets of uncovered blocks are neither generated nor traced (CoverageMask::raysIn
  /// counts their rays): a coverage mask, and not the null trace (which fakes a hit on every
  /// ray).
  bool skipUncovered;
  /// The scene's box for the scene-box test; null when the test is off or cannot resolve any
  /// ray (boxTestFor), or the coverage mask replaces it.
  const SceneBox* box;
  // The passes over each block: colour averages samples [0, colorSamples); the geometry AOVs
  // come from the centre ray, which at spp 1 is sample 0 itself (geometryFromSample) and
  // otherwise one extra ray per pixel, traced in pass colorSamples (the last of `passes`).
  int colorSamples;
  bool geometryFromSample;
  int passes;
  /// Every per-pixel channel the frame loop stores into (writtenChannels).
  std::vector<WrittenChannel> written;
  /// The channels whose misses each tile writes before its hits (missChannels; none when the
  /// storage holds them already).
  std::vector<MissChannel> misses;
  /// The packet width and trace mode, chosen here once, so no packet tests them.
  TileRenderer renderTile;
  /// RenderSettings::nullTrace: the fake primID of lane k (k mod object 0's triangle count).
  uint32_t nullPrimIds[16] = {};
};

ImagePlan::ImagePlan(const Scene& scene_, const Camera& camera_, const RenderSettings& settings_,
                     const FramePixels& px_, size_t pixelOffset_)
    : scene(scene_),
      camera(camera_),
      out(px_),
      settings(settings_),
      description(camera_.describe()),
      width(description.width),
      height(description.height),
      pixelOffset(pixelOffset_),
      eye(camera_.renderEye()),
      axis(camera_.viewAxis()),
      origin(scene_.renderOrigin()),
      color(px_.aovs.has(kAovColor)),
      depth(px_.aovs.has(kAovDepth)),
      distance(px_.aovs.has(kAovDistance)),
      normal(px_.aovs.has(kAovNormal)),
      position(px_.aovs.has(kAovPosition)),
      primId(px_.aovs.has(kAovPrimId)),
      geomId(px_.aovs.has(kAovGeomId)),
      shadingNormal(px_.aovs.has(kAovShadingNormal)),
      instanceId(px_.aovs.has(kAovInstanceId)),
      meshId(px_.aovs.has(kAovMeshId)),
      materialId(px_.aovs.has(kAovMaterialId)),
      barycentric(px_.aovs.has(kAovBarycentric)),
      uv(px_.aovs.has(kAovUv)),
      vertexColor(px_.aovs.has(kAovVertexColor)),
      albedo(px_.aovs.has(kAovAlbedo)),
      surface((px_.aovs.mask & kSurfaceAovs) != 0),
      looks(surfaceLooksFor(scene_, px_.aovs)),
      rotateNormals(settings_.normalFrame != NormalFrame::World),
      frameFromWorld(normalFrameFromWorld(settings_.normalFrame, description)),
      propertyValues(propertyTables(scene_, px_.aovs)),
      propertyDomains(domainsOf(px_.aovs)),
      meshData(shadingNormal || !px_.aovs.properties.empty() || (normal && rotateNormals) ||
               surface),
      layers(px_.aovs.layers > 0
                 ? std::optional<LayerPlan>(std::in_place, scene_, camera_, px_, eye, axis)
                 : std::nullopt),
      anyGeometry(depth || distance || normal || position || primId || geomId || shadingNormal ||
                  surface || !px_.aovs.properties.empty() || layers),
      instanced(scene_.instanceCount() > 0),
      remapPrimIds(scene_.remapsPrimIds()),
      coverage(coverageFor(scene_, camera_, settings_)),
      skipUncovered(coverage && !settings_.nullTrace),
      box(coverage ? nullptr : boxTestFor(scene_, camera_, settings_)),
      colorSamples(color ? settings_.spp : 0),
      geometryFromSample(anyGeometry && color && settings_.spp == 1),
      passes(colorSamples + (anyGeometry && !geometryFromSample ? 1 : 0)),
      written(writtenChannels(px_)),
      misses(missChannels(px_)),
      renderTile(tileRendererFor(settings_)) {
  if (layers) layers->place(width, pixelOffset);
  if (settings.nullTrace) {
    // The fake hits must name a real object and triangle (the mesh-data AOVs read them), and
    // layers would call Embree again.
    if (layers) throw Error("null trace (bench --null): layered hits (--layers) trace Embree");
    if (scene.culled()) throw Error("null trace (bench --null): not available on a culled scene");
    if (scene.objectCount() == 0) throw Error("null trace (bench --null): the scene is empty");
    const size_t triangles = scene.objectMesh(0).triangleCount();
    if (triangles == 0) throw Error("null trace (bench --null): object 0 has no triangle");
    for (size_t k = 0; k < 16; ++k) nullPrimIds[k] = uint32_t(k % triangles);
  }
}

/// One thread's Embree packet and its coherent intersection context.
template <int N>
struct PacketState : PacketBuffers<N> {
  RTCIntersectContext ctx;
  /// The packet's block sees nothing of the scene (its coverage mask leaves it uncovered):
  /// the camera did not generate its rays, and every lane in the image is a miss. Never set
  /// in the null trace, which fakes a hit on every ray.
  bool unseen = false;

  PacketState() {
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  }
};

/// Per-lane results of one traced packet: which lanes hit, and their unit normals. The
/// normals are set by unitNormals, which renderPass calls whenever an AOV reads them (colour,
/// normal, shading normal), and are not read otherwise: left unset, no packet pays to clear
/// them.
template <int N>
struct PacketHits {
  alignas(64) float nx[N], ny[N], nz[N];
  alignas(64) int hit[N];
  uint32_t bits = 0;  ///< bit k set where lane k hit: the AOV writers take it (storeHitLanes)
};

/// Colour sums of one block over its samples; renderBlock clears them when the frame has
/// colour (nothing reads them otherwise).
template <int N>
struct BlockColor {
  float shade[N], cover[N];
};

/// Keeps the lanes to trace in Embree's −1/0 mask: the camera gave a ray, the lane lies in
/// the image and Embree can trace the ray (traceableRay: finite, within Embree's range, a
/// segment in [0, ∞]). Counts the skipped rays; returns the active lane count. Branch-free
/// over the lanes, so it compiles to vector compares. intersect<N> then seals only the masked
/// lanes (sealMaskedLanes) instead of testing every ray again.
template <int N>
int selectLanes(const ImagePlan& plan, const PacketRequest& req, PacketState<N>& st,
                TileCounters& count) {
  constexpr int kBW = blockWidthFor(N);
  const RayLanes& l = st.lanes;
  const float *ox = l.orgX, *oy = l.orgY, *oz = l.orgZ, *dx = l.dirX, *dy = l.dirY, *dz = l.dirZ;
  const float *tnear = l.tnear, *tfar = l.tfar;
  int* __restrict valid = st.valid;
  // Locals: the stores to valid[] could otherwise alias them and force reloads every lane.
  const int x0 = req.x0, y0 = req.y0, width = plan.width, height = plan.height;
  int active = 0, untraceable = 0;
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {  // 0/1 integers and & rather than && (no branches)
    const int live = int(valid[k] != 0) & int(laneInImage(x0, y0, kBW, k, width, height));
    const int ok = traceableRay(ox[k], oy[k], oz[k], dx[k], dy[k], dz[k], tnear[k], tfar[k]);
    untraceable += live & (ok ^ 1);
    valid[k] = -(live & ok);
    active += live & ok;
  }
  count.skipped += uint64_t(untraceable);
  return active;
}

/// The stand-in for intersect<N> of RenderSettings::nullTrace: every lane hits with the fake
/// values documented there (Ng = −dir, so the eye-light shade is 1).
template <int N>
void fakeHits(const ImagePlan& plan, PacketState<N>& st) {
  auto& h = st.packet.hit;
  const RayLanes& l = st.lanes;
  float *ngX, *ngY, *ngZ, *u, *v;
  unsigned *geomID, *primID, *instID;
  if constexpr (N == 1) {
    ngX = &h.Ng_x, ngY = &h.Ng_y, ngZ = &h.Ng_z, u = &h.u, v = &h.v;
    geomID = &h.geomID, primID = &h.primID, instID = &h.instID[0];
  } else {
    ngX = h.Ng_x, ngY = h.Ng_y, ngZ = h.Ng_z, u = h.u, v = h.v;
    geomID = h.geomID, primID = h.primID, instID = h.instID[0];
  }
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {
    l.tfar[k] = 1.0f;
    ngX[k] = -l.dirX[k], ngY[k] = -l.dirY[k], ngZ[k] = -l.dirZ[k];
    u[k] = 0.25f, v[k] = 0.25f;
    geomID[k] = 0, primID[k] = plan.nullPrimIds[k], instID[k] = RTC_INVALID_GEOMETRY_ID;
  }
}

/// The scene-box test (RenderSettings::sceneBoxTest) on the `active` lanes of `st`: clears
/// the lanes whose rays miss the scene's box, which are misses, and counts them; returns the
/// lanes left for Embree. The null trace runs the test, so its cost is in `bench --null`, on a
/// copy of the lane mask: there every lane still fakes a hit.
template <int N, bool kNull>
int resolveLanesMissingBox(const ImagePlan& plan, PacketState<N>& st, int active,
                           TileCounters& count) {
  if (!plan.box) return active;
  if constexpr (kNull) {
    alignas(64) int copy[N];
    std::memcpy(copy, st.valid, sizeof copy);
    count.outsideBox += uint64_t(maskLanesMissingBox<N>(*plan.box, st.lanes, copy));
    return active;
  } else {
    const int missed = maskLanesMissingBox<N>(*plan.box, st.lanes, st.valid);
    count.outsideBox += uint64_t(missed);
    return active - missed;
  }
}

/// Intersects the packet of `req`, whose rays the camera has generated into `st` (kNull:
/// fakeHits instead of Embree); false when no lane can have hit (none was traced, or the
/// scene-box test resolved every one as a miss).
template <int N, bool kNull>
bool tracePacket(const ImagePlan& plan, const PacketRequest& req, PacketState<N>& st,
                 TileCounters& count) {
  if (st.unseen) {
    // The lanes that would have been valid and finite: the counts of the generated packet.
    const uint64_t lanes =
        uint64_t(plan.coverage->raysIn(req.y0, req.x0, blockWidthFor(N), blockHeightFor(N)));
    count.traced += lanes;
    count.outsideBox += lanes;
    return false;
  }
  const int active = selectLanes<N>(plan, req, st, count);
  if (active == 0) return false;
  count.traced += uint64_t(active);
  // The null trace generates the rays of uncovered blocks and fakes their hits too; the count
  // says what the mask would have resolved.
  if (kNull && plan.coverage && !plan.coverage->covers(req.y0, req.x0))
    count.outsideBox += uint64_t(active);
  if (resolveLanesMissingBox<N, kNull>(plan, st, active, count) == 0) return false;
  if constexpr (kNull) {
    fakeHits<N>(plan, st);
  } else {
    clearHits<N>(st.packet);
    // selectLanes tested every active lane with traceableRay; later steps only clear lanes.
    intersectScene<N>(plan.scene, &st.ctx, st.valid, st.packet, true);
  }
  return true;
}

/// Marks the traced lanes that hit (1, else 0, and as bits); returns their number (one count
/// of the bits, not a second reduction over the lanes).
template <int N>
int findHits(const PacketState<N>& st, PacketHits<N>& out) {
  uint32_t bits = 0;
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {  // & rather than &&: no branch, vector compares
    out.hit[k] = int(st.valid[k] != 0) & int(st.hits.geomID[k] != RTC_INVALID_GEOMETRY_ID);
    bits |= uint32_t(out.hit[k]) << k;
  }
  out.bits = bits;
  return __builtin_popcount(bits);
}

/// n = g / |g| for each of the N lanes; 0 where g has zero length. Restrict parameters: GCC
/// honours them and needs no run-time alias checks (it does not honour restrict locals).
template <int N>
void normalizeLanes(const float* __restrict gx, const float* __restrict gy,
                    const float* __restrict gz, float* __restrict nx, float* __restrict ny,
                    float* __restrict nz) {
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {
    const float len2 = gx[k] * gx[k] + gy[k] * gy[k] + gz[k] * gz[k];
    const float inv = len2 > 0.0f ? 1.0f / std::sqrt(len2) : 0.0f;
    nx[k] = gx[k] * inv, ny[k] = gy[k] * inv, nz[k] = gz[k] * inv;
  }
}

/// Unit geometric normals in world space (instanced hits through the instance's normal
/// matrix); 0 where Embree's normal has zero length.
template <int N>
void unitNormals(const ImagePlan& plan, const PacketState<N>& st, PacketHits<N>& out) {
  const HitLanes& h = st.hits;
  if (!plan.instanced) return normalizeLanes<N>(h.ngX, h.ngY, h.ngZ, out.nx, out.ny, out.nz);
  alignas(64) float gx[N], gy[N], gz[N];
  for (int k = 0; k < N; ++k) {
    glm::vec3 g(h.ngX[k], h.ngY[k], h.ngZ[k]);
    if (out.hit[k] && h.instID[k] != RTC_INVALID_GEOMETRY_ID)
      g = plan.scene.normalFromMesh(h.instID[k]) * g;
    gx[k] = g.x, gy[k] = g.y, gz[k] = g.z;
  }
  normalizeLanes<N>(gx, gy, gz, out.nx, out.ny, out.nz);
}

/// Adds the eye-light shading |N·D| and the coverage of the hit lanes to the block's sums.
template <int N>
void accumulateColor(const PacketState<N>& st, const PacketHits<N>& h, BlockColor<N>& color) {
  const RayLanes& l = st.lanes;
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {
    const float c = std::fabs(h.nx[k] * l.dirX[k] + h.ny[k] * l.dirY[k] + h.nz[k] * l.dirZ[k]);
    color.shade[k] += h.hit[k] ? c : 0.0f;
    color.cover[k] += h.hit[k] ? 1.0f : 0.0f;
  }
}

/// Planar depth of every lane: (org − eye)·axis + t·(dir·axis).
template <int N>
void planarDepths(const ImagePlan& plan, const PacketState<N>& st, float* z) {
  const RayLanes& l = st.lanes;
  const glm::vec3 e = plan.eye, a = plan.axis;
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k)
    z[k] = (l.orgX[k] - e.x) * a.x + (l.orgY[k] - e.y) * a.y + (l.orgZ[k] - e.z) * a.z +
           st.hits.tfar[k] * (l.dirX[k] * a.x + l.dirY[k] * a.y + l.dirZ[k] * a.z);
}

/// The object of a hit: the instance, or the geometry when the mesh is attached directly.
inline unsigned objectId(const HitLanes& h, int k) {
  // Both loaded first: a load under the condition kept the geomid lane loop scalar.
  const unsigned instance = h.instID[k], geometry = h.geomID[k];
  return instance == RTC_INVALID_GEOMETRY_ID ? geometry : instance;
}

/// Where a block's lanes land in one framebuffer channel: the block's top-left pixel, the
/// channel's row stride and how many of the block's rows and columns lie in the image.
template <int N>
struct BlockPixels {
  static constexpr int kBW = blockWidthFor(N), kBH = blockHeightFor(N);
  size_t first;   ///< pixel index of the block's top-left pixel
  size_t stride;  ///< pixels per framebuffer row
  int rows, columns;

  BlockPixels(const ImagePlan& plan, const PacketRequest& req)
      : first(plan.pixelOffset + size_t(req.y0) * size_t(plan.width) + size_t(req.x0)),
        stride(size_t(plan.width)),
        rows(std::min(kBH, plan.height - req.y0)),
        columns(std::min(kBW, plan.width - req.x0)) {}
};

/// Writes value[k] of every hit lane k to its pixel of a channel of kC interleaved components
/// (value[c] holds component c), leaving the other pixels as they are; bit k of `hitBits` is
/// set where hit[k] != 0 (PacketHits::bits). A block whose rows lie whole in the image writes
/// row by row, reading a row's old pixels back only when it is partly hit
/// (core/engine/interleaved_row.h; the tile is this thread's alone, so the read-back is safe); a
/// block cut by the right edge stores lane by lane.
template <int N, int kC, class T>
void storeHitLanes(const BlockPixels<N>& px, const int* hit, uint32_t hitBits,
                   const T* const (&value)[kC], T* channel) {
  constexpr int kBW = BlockPixels<N>::kBW;
  T* const base = channel + kC * px.first;
  if (px.columns == kBW) {
    for (int r = 0; r < px.rows; ++r) {
      T* __restrict row = base + kC * size_t(r) * px.stride;
      const int l = r * kBW;
      const unsigned rowBits = (hitBits >> l) & ((1u << kBW) - 1u);
      if constexpr (kBW == 4 && kC == 1) {
        blendRow4<T>(value[0] + l, hit + l, rowBits, row);
        continue;
      }
      if constexpr (kBW == 4 && kC == 3 && std::is_same_v<T, float>) {
        blendInterleavedRow4x3(value[0] + l, value[1] + l, value[2] + l, hit + l, rowBits, row);
        continue;
      }
      for (int j = 0; j < kBW; ++j)
        for (int c = 0; c < kC; ++c)
          row[kC * j + c] = hit[l + j] ? value[c][l + j] : row[kC * j + c];
    }
    return;
  }
  for (int r = 0; r < px.rows; ++r)
    for (int j = 0; j < px.columns; ++j)
      if (hit[r * kBW + j])
        for (int c = 0; c < kC; ++c)
          base[kC * (size_t(r) * px.stride + size_t(j)) + size_t(c)] = value[c][r * kBW + j];
}

/// Hit points in world space: render-space origin + org + t·dir in double, rounded once.
template <int N>
void worldPositions(const ImagePlan& plan, const PacketState<N>& st, float* x, float* y, float* z) {
  const RayLanes& l = st.lanes;
  const glm::dvec3 o = plan.origin;
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {
    const double t = st.hits.tfar[k];
    x[k] = float((o.x + double(l.orgX[k])) + t * double(l.dirX[k]));
    y[k] = float((o.y + double(l.orgY[k])) + t * double(l.dirY[k]));
    z[k] = float((o.z + double(l.orgZ[k])) + t * double(l.dirZ[k]));
  }
}

/// The primitive id of every lane as the user's mesh numbers it (Scene::sourcePrimId).
template <int N>
void primIds(const ImagePlan& plan, const PacketState<N>& st, const int* hit, uint32_t* out) {
  if (!plan.remapPrimIds) {
    std::memcpy(out, st.hits.primID, sizeof(uint32_t) * N);
    return;
  }
  for (int k = 0; k < N; ++k)
    out[k] = hit[k] ? plan.scene.sourcePrimId(objectId(st.hits, k), st.hits.primID[k]) : 0;
}

/// Stores the geometry AOVs of every hit lane of the packet of `req` (misses keep the
/// storage's miss values): one pass per requested AOV, only its buffer touched.
template <int N>
void storeGeometryAovs(const ImagePlan& plan, const PacketRequest& req, const PacketState<N>& st,
                       const PacketHits<N>& h) {
  const AovStores& out = plan.out;
  const BlockPixels<N> px(plan, req);
  if (plan.depth) {
    alignas(64) float z[N];
    planarDepths<N>(plan, st, z);
    storeHitLanes<N, 1, float>(px, h.hit, h.bits, {z}, out.depth);
  }
  if (plan.distance) storeHitLanes<N, 1, float>(px, h.hit, h.bits, {st.hits.tfar}, out.distance);
  if (plan.normal) storeHitLanes<N, 3, float>(px, h.hit, h.bits, {h.nx, h.ny, h.nz}, out.normal);
  if (plan.position) {
    alignas(64) float x[N], y[N], z[N];
    worldPositions<N>(plan, st, x, y, z);
    storeHitLanes<N, 3, float>(px, h.hit, h.bits, {x, y, z}, out.position);
  }
  if (plan.primId) {
    alignas(64) uint32_t ids[N];
    primIds<N>(plan, st, h.hit, ids);
    storeHitLanes<N, 1, uint32_t>(px, h.hit, h.bits, {ids}, out.primId);
  }
  if (plan.geomId) {
    alignas(64) uint32_t ids[N];
    APERTURE_LANE_LOOP
    for (int k = 0; k < N; ++k) ids[k] = objectId(st.hits, k);
    storeHitLanes<N, 1, uint32_t>(px, h.hit, h.bits, {ids}, out.geomId);
  }
}

/// The corner (0, 1, 2 in index-buffer order) with the largest barycentric weight
/// (1 − u − v, u, v); ties go to the lowest corner.
inline int nearestCorner(float u, float v) {
  const float w[3] = {1.0f - u - v, u, v};
  int c = 0;
  if (w[1] > w[c]) c = 1;
  if (w[2] > w[c]) c = 2;
  return c;
}

/// `n` normalised, or `fallback` when it has zero length.
inline glm::vec3 unitOr(const glm::vec3& n, const glm::vec3& fallback) {
  const float len2 = glm::dot(n, n);
  return len2 > 0.0f ? n / std::sqrt(len2) : fallback;
}

/// `n` values per vertex of `data` at the triangle's `corner`s weighted by `w`, into `out`.
template <int kN>
inline void interpolateCorners(const float* data, const uint32_t* corner, const float (&w)[3],
                               float* out) {
  for (int a = 0; a < kN; ++a)
    out[a] = w[0] * data[kN * size_t(corner[0]) + size_t(a)] +
             w[1] * data[kN * size_t(corner[1]) + size_t(a)] +
             w[2] * data[kN * size_t(corner[2]) + size_t(a)];
}

/// Stores the surface AOVs (kSurfaceAovs) of a hit on triangle `prim` of object `object`
/// (barycentrics u, v) at pixel px: the ids, Embree's u, v, and the texture coordinates,
/// vertex colour and albedo interpolated with (1 − u − v, u, v) over the corners in
/// index-buffer order. Albedo = base colour × texture at the uv (when the material has one) ×
/// vertex colour (when the mesh has colours).
inline void storeSurfaceLane(const ImagePlan& plan, unsigned object, uint32_t prim,
                             const Mesh& mesh, const uint32_t* corner, float u, float v,
                             size_t px) {
  const AovStores& out = plan.out;
  const ObjectIds& ids = plan.scene.objectIds(object);
  if (plan.instanceId) out.instanceId[px] = ids.instanceOfTriangle(mesh.faceGroups, prim);
  if (plan.meshId) out.meshId[px] = ids.mesh;
  const uint32_t material =
      ids.materialBase + (mesh.faceMaterials.empty() ? 0u : mesh.faceMaterials[prim]);
  if (plan.materialId) out.materialId[px] = material;
  if (plan.barycentric) out.barycentric[2 * px] = u, out.barycentric[2 * px + 1] = v;
  if (!plan.uv && !plan.vertexColor && !plan.albedo) return;
  const float w[3] = {1.0f - u - v, u, v};
  float st[2] = {0.0f, 0.0f}, cd[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  if (!mesh.texcoords.empty()) interpolateCorners<2>(mesh.texcoords.data(), corner, w, st);
  if (!mesh.vertexColors.empty()) interpolateCorners<4>(mesh.vertexColors.data(), corner, w, cd);
  if (plan.uv) out.uv[2 * px] = st[0], out.uv[2 * px + 1] = st[1];
  if (plan.vertexColor)
    for (int c = 0; c < 4; ++c) out.vertexColor[4 * px + size_t(c)] = cd[c];
  if (plan.albedo) {
    const Material& m = plan.looks->materials[material];
    glm::vec4 a = m.baseColor * glm::vec4(cd[0], cd[1], cd[2], cd[3]);
    if (m.baseColorTexture >= 0)
      a *= plan.looks->textures->sample(m.baseColorTexture, st[0], st[1]);
    for (int c = 0; c < 4; ++c) out.albedo[4 * px + size_t(c)] = a[c];
  }
}

/// Stores the AOVs read from the hit mesh's data for hit lane k at pixel px: the shading
/// normal, the property channels, the surface AOVs (storeSurfaceLane), and the normal (and
/// shading normal) in the plan's frame.
/// Shading normal: the triangle's vertex normals interpolated with Embree's u, v, through the
/// instance's normal matrix, normalised; the geometric normal for a mesh without vertex
/// normals (or where the interpolated normal vanishes).
template <int N>
void storeMeshDataLane(const ImagePlan& plan, const PacketState<N>& st, const PacketHits<N>& h,
                       int k, size_t px) {
  const AovStores& out = plan.out;
  const unsigned object = objectId(st.hits, k);
  const uint32_t prim =
      plan.remapPrimIds ? plan.scene.meshTriangle(object, st.hits.primID[k]) : st.hits.primID[k];
  const Mesh& mesh = plan.scene.objectMesh(object);
  const uint32_t* corner = &mesh.indices[3 * size_t(prim)];
  const float u = st.hits.u[k], v = st.hits.v[k];
  // The unit geometric normal in world space; set (unitNormals) only where these AOVs need it.
  const auto geometricNormal = [&] { return glm::vec3(h.nx[k], h.ny[k], h.nz[k]); };
  if (plan.shadingNormal) {
    glm::vec3 ns = geometricNormal();
    if (!mesh.vertexNormals.empty()) {
      const float w[3] = {1.0f - u - v, u, v};
      glm::vec3 sum;
      interpolateCorners<3>(mesh.vertexNormals.data(), corner, w, &sum.x);
      if (st.hits.instID[k] != RTC_INVALID_GEOMETRY_ID)
        sum = plan.scene.normalFromMesh(st.hits.instID[k]) * sum;
      ns = unitOr(sum, geometricNormal());
    }
    if (plan.rotateNormals) ns = plan.frameFromWorld * ns;
    for (int a = 0; a < 3; ++a) out.shadingNormal[3 * px + size_t(a)] = ns[a];
  }
  if (plan.normal && plan.rotateNormals) {
    const glm::vec3 n = plan.frameFromWorld * geometricNormal();
    for (int a = 0; a < 3; ++a) out.normal[3 * px + size_t(a)] = n[a];
  }
  for (size_t j = 0; j < out.properties.size(); ++j) {
    const uint32_t* values = plan.propertyValues[j][object];
    out.properties[j][px] = plan.propertyDomains[j] == PropertyDomain::Face
                                ? values[prim]
                                : values[corner[nearestCorner(u, v)]];
  }
  if (plan.surface) storeSurfaceLane(plan, object, prim, mesh, corner, u, v, px);
}

/// Stores the mesh data AOVs (storeMeshDataLane) of every hit lane of the packet of `req`.
template <int N>
void storeMeshData(const ImagePlan& plan, const PacketRequest& req, const PacketState<N>& st,
                   const PacketHits<N>& h) {
  constexpr int kBW = blockWidthFor(N);
  const int x0 = req.x0, y0 = req.y0, width = plan.width;  // not reloaded after stores
  const size_t offset = plan.pixelOffset;
  for (int k = 0; k < N; ++k) {
    if (!h.hit[k]) continue;
    const LanePixel p = lanePixel(x0, y0, kBW, k);
    storeMeshDataLane<N>(plan, st, h, k, offset + size_t(p.row) * size_t(width) + size_t(p.column));
  }
}

template <int N>
void storeGeometry(const ImagePlan& plan, const PacketRequest& req, const PacketState<N>& st,
                   const PacketHits<N>& h) {
  storeGeometryAovs<N>(plan, req, st, h);
  if (plan.meshData) storeMeshData<N>(plan, req, st, h);
}

/// Traces the packet of `req` (its rays already in `st`); adds its shading to `color` when given,
/// and stores the geometry AOVs when `geometry` is set.
template <int N, bool kNull>
void renderPass(const ImagePlan& plan, const PacketRequest& req, PacketState<N>& st,
                BlockColor<N>* color, bool geometry, TileCounters& count) {
  if (!tracePacket<N, kNull>(plan, req, st, count)) return;
  PacketHits<N> hits;
  const int hitLanes = findHits<N>(st, hits);
  if (hitLanes == 0) return;
  count.hits += uint64_t(hitLanes);
  if (color || (geometry && (plan.normal || plan.shadingNormal))) unitNormals<N>(plan, st, hits);
  if (color) accumulateColor<N>(st, hits, *color);
  if (geometry) storeGeometry<N>(plan, req, st, hits);
  if (geometry && plan.layers) traceLayers<N>(*plan.layers, req, st.hits, hits.hit);
}

/// Writes the block's colour: the mean of its samples (R = G = B = shade, A = coverage), to
/// every lane in the image (storeHitLanes with every lane "hit": whole rows are plain stores).
template <int N>
void storeColor(const ImagePlan& plan, const PacketRequest& req, const BlockColor<N>& color) {
  const float inv = 1.0f / float(plan.colorSamples);
  alignas(64) float shade[N], cover[N];
  alignas(64) int every[N];
  APERTURE_LANE_LOOP
  for (int k = 0; k < N; ++k) {
    shade[k] = color.shade[k] * inv;
    cover[k] = color.cover[k] * inv;
    every[k] = 1;
  }
  storeHitLanes<N, 4, float>(BlockPixels<N>(plan, req), every, uint32_t((uint64_t(1) << N) - 1),
                             {shade, shade, shade, cover}, plan.out.rgba);
}

/// This thread's two packets of width N, which PacketPipeline fills in turn. In thread-local
/// storage rather than on the frame loop's stack: TBB keeps its task-tree nodes on the stack
/// below a parallel loop's caller and may touch them after the caller resumed
/// (core/util/parallel.h), and ThreadSanitizer reported those late touches as races with the
/// packets written there (twice in this project's CI rehearsals, in a render subprocess; the
/// worker's stack not restorable, so no suppression matches). A thread renders one tile at a time,
/// so one pair per thread suffices.
template <int N>
PacketState<N>* threadPackets() {
  static thread_local PacketState<N> packets[2];
  return packets;
}

/// A tile's packets in render order, block by block (rows of blocks, left to right) and
/// within a block pass by pass, with the rays of the next packet generated before the current
/// one is traced: the camera's long dependency chain (square roots and divides per ray) then
/// overlaps the tracing and stores of the packet before it instead of stalling them. Cameras are
/// pure functions of the request, so the order of generation changes no ray.
template <int N>
class PacketPipeline {
 public:
  static constexpr int kBW = blockWidthFor(N), kBH = blockHeightFor(N);

  PacketPipeline(const ImagePlan& plan, int x0, int y0, int x1, int y1)
      : plan_(plan),
        x0_(x0),
        x1_(x1),
        y1_(y1),
        next_{x0, y0, kBW, kBH, sampleOf(0)},
        more_(x0 < x1 && y0 < y1) {
    if (more_) generateNext();
  }

  /// Whether packets are left.
  bool more() const { return more_; }
  /// The top row of the next packet's block.
  int nextBlockRow() const { return next_.y0; }
  /// The next packet's request and its state, holding its rays; generates the packet after
  /// it into the other buffer. The state stays valid until the next call.
  PacketState<N>& advance(PacketRequest& req) {
    req = next_;
    PacketState<N>& current = states_[slot_];
    slot_ ^= 1;
    more_ = step();
    if (more_) generateNext();
    return current;
  }

 private:
  int sampleOf(int pass) const {
    return pass == plan_.colorSamples ? PacketRequest::kCentreRay : pass;
  }
  /// Moves next_ to the request after it; false past the tile's last packet.
  bool step() {
    if (++pass_ < plan_.passes) {
      next_.sample = sampleOf(pass_);
      return true;
    }
    pass_ = 0;
    next_.sample = sampleOf(0);
    if ((next_.x0 += kBW) < x1_) return true;
    next_.x0 = x0_;
    return (next_.y0 += kBH) < y1_;
  }
  /// Generates the rays of next_, unless its block is unseen (PacketState::unseen).
  void generateNext() {
    PacketState<N>& st = states_[slot_];
    st.unseen = plan_.skipUncovered && !plan_.coverage->covers(next_.y0, next_.x0);
    if (!st.unseen) plan_.camera.generate(next_, st.lanes, st.valid);
  }

  const ImagePlan& plan_;
  const int x0_, x1_, y1_;
  PacketRequest next_;
  int pass_ = 0, slot_ = 0;
  bool more_;
  PacketState<N>* const states_ = threadPackets<N>();  // two
};

/// Renders the next block of the pipeline: the colour samples, then the centre ray when it
/// is a pass of its own. One call site of renderPass, so the compiler inlines the whole pass
/// into the block loop.
template <int N, bool kNull>
void renderBlock(const ImagePlan& plan, PacketPipeline<N>& packets, TileCounters& count) {
  BlockColor<N> color;
  if (plan.color) color = BlockColor<N>{};
  PacketRequest req;
  for (int pass = 0; pass < plan.passes; ++pass) {
    PacketState<N>& st = packets.advance(req);
    const bool centre = req.centreRay();  // the pipeline maps passes to samples (sampleOf)
    renderPass<N, kNull>(plan, req, st, centre ? nullptr : &color,
                         centre || plan.geometryFromSample, count);
  }
  if (plan.color) storeColor<N>(plan, {req.x0, req.y0, req.blockW, req.blockH, 0}, color);
}

/// Asks for the cache lines of pixels [x0, x1) of rows [y0, y1) of every channel the frame
/// loop writes (ImagePlan::written), into L2 (prefetcht1: the lines stay out of the L1 that
/// Embree's traversal works in). A frame's framebuffer does not stay cached, so the AOV stores
/// of a block would otherwise miss: on Intel the missing stores fill the store buffer and
/// stall the stores that follow, Embree's among them (bench/RESULTS.md, issue 13, eighth
/// session, measured on a Xeon).
inline void prefetchPixelRows(const ImagePlan& plan, int x0, int x1, int y0, int y1) {
  // Inline assembly, volatile: GCC deems __builtin_prefetch free of side effects, so it found
  // this function without any (ipa-pure-const) and deleted every call to it. Elsewhere than
  // x86-64 the builtin stays, and GCC may drop it there.
  const auto prefetchIntoL2 = [](uintptr_t line) {
#if defined(__x86_64__)
    asm volatile("prefetcht1 %0" : : "m"(*reinterpret_cast<const char*>(line)));
#else
    __builtin_prefetch(reinterpret_cast<const char*>(line), 1, 2);
#endif
  };
  constexpr uintptr_t kLine = 64;
  for (const WrittenChannel& c : plan.written)
    for (int y = y0; y < y1; ++y) {
      const size_t first = plan.pixelOffset + size_t(y) * size_t(plan.width) + size_t(x0);
      // Addresses as integers: the first line may begin before the channel's first pixel.
      const uintptr_t begin = reinterpret_cast<uintptr_t>(c.pixels + first * c.bytesPerPixel);
      const uintptr_t end = begin + size_t(x1 - x0) * c.bytesPerPixel;
      for (uintptr_t line = begin - begin % kLine; line < end; line += kLine) prefetchIntoL2(line);
    }
}

/// The columns [x0, x1) of the blocks of the block row at y in columns [tx0, tx1) that may
/// write pixels: from the first to the last block the coverage mask keeps (every block without
/// one); empty (x0 == x1) when it keeps none.
template <int N>
std::pair<int, int> writtenSpanOfBlockRow(const ImagePlan& plan, int y, int tx0, int tx1) {
  if (!plan.skipUncovered) return {tx0, tx1};
  constexpr int kBW = blockWidthFor(N);
  int first = tx1, last = tx0;
  for (int x = tx0; x < tx1; x += kBW)
    if (plan.coverage->covers(y, x)) first = std::min(first, x), last = x + kBW;
  return first < last ? std::pair{first, std::min(last, tx1)} : std::pair{tx0, tx0};
}

/// Prefetches the framebuffer rows of the block row at y (prefetchPixelRows), where blocks may
/// write; nothing past the tile's last row y1.
template <int N>
void prefetchBlockRow(const ImagePlan& plan, int y, int x0, int x1, int y1) {
  if (y >= y1) return;
  const auto [first, last] = writtenSpanOfBlockRow<N>(plan, y, x0, x1);
  if (first < last) prefetchPixelRows(plan, first, last, y, std::min(y1, y + blockHeightFor(N)));
}

/// Renders the tile of columns [x0, x1) and rows [y0, y1), block by block (a TileRenderer).
/// A per-ISA kernel (core/util/vector_kernel.h): the whole block loop, stores included, is
/// compiled for each x86-64 level.
template <int N, bool kNull>
void renderTile(const ImagePlan& plan, int x0, int y0, int x1, int y1, TileCounters& count) {
  // Denormals flushed on every worker (Embree's recommendation); same mode on all threads.
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
  // Under TSan: the stack below this frame's base is dead (its locals not yet written), but a
  // TBB worker of an earlier loop may have touched TBB nodes there after its caller resumed
  // (core/util/parallel.h); the hit lanes and AOV values written there would be reported racing
  // with it. The packets themselves are thread-local (threadPackets). Compiled out otherwise.
  APERTURE_TSAN_FORGET_STACK_BELOW(__builtin_frame_address(0));
  PacketPipeline<N> packets(plan, x0, y0, x1, y1);
  // The framebuffer lines of the block row after the one being rendered are prefetched.
  constexpr int kBH = blockHeightFor(N);
  prefetchBlockRow<N>(plan, y0, x0, x1, y1);
  prefetchBlockRow<N>(plan, y0 + kBH, x0, x1, y1);
  for (int row = y0; packets.more();) {
    if (packets.nextBlockRow() != row) {
      row = packets.nextBlockRow();
      prefetchBlockRow<N>(plan, row + kBH, x0, x1, y1);
    }
    renderBlock<N, kNull>(plan, packets, count);
  }
}

template <bool kNull>
TileRenderer tileRendererOfWidth(int packetWidth) {
  switch (packetWidth) {
    case 1:
      return &Kernel<&renderTile<1, kNull>>::run;
    case 4:
      return &Kernel<&renderTile<4, kNull>>::run;
    case 8:
      return &Kernel<&renderTile<8, kNull>>::run;
    default:
      return &Kernel<&renderTile<16, kNull>>::run;
  }
}

TileRenderer tileRendererFor(const RenderSettings& settings) {
  return settings.nullTrace ? tileRendererOfWidth<true>(settings.packetWidth)
                            : tileRendererOfWidth<false>(settings.packetWidth);
}

/// Throws Error, its message starting with `who`, unless `px` can hold `frames` frames of the
/// camera image `image` stacked as rows: some pixel and some AOV, storage for every channel and
/// `image.width` x (`frames` · `image.height`) pixels. The one check of a frame's storage that
/// renderImage, renderImages and renderImagesStacked share.
void checkFrameStorage(const std::string& who, const FramePixels& px,
                       const CameraDescription& image, size_t frames) {
  if (px.width <= 0 || px.height <= 0 || px.aovs.empty())
    throw Error(cat(who, ": framebuffer ", px.width, "x", px.height, " with AOVs '",
                    aovListString(px.aovs), "' is empty"));
  for (const PixelChannel& c : px.channels)
    if (!c.data) throw Error(cat(who, ": AOV '", c.name, "' has no storage"));
  if (px.width != image.width || size_t(px.height) != size_t(image.height) * frames)
    throw Error(cat(who, ": framebuffer ", px.width, "x", px.height, " does not hold ", frames,
                    frames == 1 ? " frame" : " frames", " of the camera image ", image.width, "x",
                    image.height));
}

/// Writes the miss value of every value of the tile of columns [x0, x1) and rows [y0, y1) of
/// the plan's image, in every channel and layer of ImagePlan::misses: before its hits, on the
/// thread that renders it.
void writeTileMisses(const ImagePlan& plan, int x0, int y0, int x1, int y1) {
  for (const MissChannel& m : plan.misses)
    for (size_t layer = 0; layer < m.layers; ++layer)
      for (int y = y0; y < y1; ++y) {
        const size_t pixel = plan.pixelOffset + size_t(y) * size_t(plan.width) + size_t(x0);
        std::fill_n(m.data + layer * m.layerStride + pixel * m.channels,
                    size_t(x1 - x0) * m.channels, m.bits);
      }
}

}  // namespace

namespace {

/// When a render call started: its frames' seconds count from there.
using TimePoint = std::chrono::steady_clock::time_point;

/// Work counters of one frame, summed over its tiles.
struct FrameProgress {
  std::atomic<uint64_t> traced{0}, skipped{0}, outsideBox{0}, hits{0};
  std::atomic<size_t> tilesLeft{0};
};

/// The one parallel loop over (frame, tile) behind renderImage, renderImages and
/// renderImagesStacked: the frames' tiles are numbered one after another (frame k owns tiles
/// [firstTile[k], firstTile[k + 1])), so small frames keep every core busy. Returns each
/// frame's stats, each frame's seconds counted from `start` (the caller's entry, so the
/// plans' per-frame work, the coverage mask included, is timed); `progress` as renderImages
/// documents it.
std::vector<RenderStats> renderPlans(const std::deque<ImagePlan>& plans,
                                     const std::function<void(size_t)>& progress, TimePoint start) {
  const size_t n = plans.size();
  std::vector<size_t> firstTile(n + 1, 0);
  std::unique_ptr<FrameProgress[]> frames(new FrameProgress[n]);
  for (size_t k = 0; k < n; ++k) {
    const int ts = plans[k].settings.tileSize;
    const size_t tiles =
        size_t((plans[k].width + ts - 1) / ts) * size_t((plans[k].height + ts - 1) / ts);
    frames[k].tilesLeft = tiles;
    firstTile[k + 1] = firstTile[k] + tiles;
  }
  std::vector<RenderStats> stats(n);
  std::mutex progressMutex;
  size_t framesDone = 0;
  parallelFor(firstTile[n], 1, [&](size_t first, size_t last) {
    for (size_t tile = first; tile != last; ++tile) {
      const size_t k =
          size_t(std::upper_bound(firstTile.begin(), firstTile.end(), tile) - firstTile.begin()) -
          1;
      const ImagePlan& plan = plans[k];
      const int ts = plan.settings.tileSize;
      const int tilesX = (plan.width + ts - 1) / ts, local = int(tile - firstTile[k]);
      const int x0 = (local % tilesX) * ts, y0 = (local / tilesX) * ts;
      const int x1 = std::min(x0 + ts, plan.width), y1 = std::min(y0 + ts, plan.height);
      TileCounters c;
      writeTileMisses(plan, x0, y0, x1, y1);
      plan.renderTile(plan, x0, y0, x1, y1, c);
      FrameProgress& f = frames[k];
      f.traced += c.traced;
      f.skipped += c.skipped;
      f.outsideBox += c.outsideBox;
      f.hits += c.hits;
      if (--f.tilesLeft != 0) continue;
      // The frame's last tile: its counters are complete (every other tile decremented
      // tilesLeft after adding its counts).
      stats[k].seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      stats[k].raysTraced = f.traced;
      stats[k].raysSkipped = f.skipped;
      stats[k].raysOutsideBox = f.outsideBox;
      if (plan.coverage) stats[k].maskCovered = plan.coverage->coveredFraction();
      stats[k].boxTested = plan.box != nullptr;
      stats[k].hits = f.hits;
      if (!progress) continue;
      const std::lock_guard<std::mutex> lock(progressMutex);
      progress(++framesDone);
    }
  });
  return stats;
}

/// `settings` with the camera's own spp.
RenderSettings settingsFor(const Camera& camera, const RenderSettings& settings) {
  RenderSettings s = settings;
  s.spp = camera.describe().spp;
  return s;
}

}  // namespace

RenderStats renderImage(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                        Framebuffer& fb) {
  const TimePoint start = std::chrono::steady_clock::now();
  validateRenderSettings(settings);
  const FramePixels px = framePixelsOf(fb);
  const CameraDescription image = camera.describe();
  checkFrameStorage("renderImage", px, image, 1);
  if (image.spp != settings.spp)
    throw Error(cat("renderImage: the camera's spp ", image.spp,
                    " does not match the settings' spp ", settings.spp));
  std::deque<ImagePlan> plans;
  plans.emplace_back(scene, camera, settings, px);
  return renderPlans(plans, {}, start).front();
}

std::vector<RenderStats> renderImages(const Scene& scene, const std::vector<const Camera*>& cameras,
                                      const RenderSettings& settings,
                                      std::vector<Framebuffer>& framebuffers,
                                      const std::function<void(size_t)>& progress) {
  std::vector<FramePixels> frames;
  for (Framebuffer& fb : framebuffers) frames.push_back(framePixelsOf(fb));
  return renderImages(scene, cameras, settings, frames, progress);
}

std::vector<RenderStats> renderImages(const Scene& scene, const std::vector<const Camera*>& cameras,
                                      const RenderSettings& settings,
                                      const std::vector<FramePixels>& frames,
                                      const std::function<void(size_t)>& progress) {
  const TimePoint start = std::chrono::steady_clock::now();
  validateRenderSettings(settings);
  if (cameras.size() != frames.size())
    throw Error(
        cat("renderImages: ", cameras.size(), " cameras but ", frames.size(), " framebuffers"));
  std::deque<ImagePlan> plans;  // a deque: plans are not movable (references)
  for (size_t k = 0; k < cameras.size(); ++k) {
    APERTURE_CHECK_OP(cameras[k], !=, nullptr);
    const RenderSettings forCamera = settingsFor(*cameras[k], settings);
    checkFrameStorage(cat("renderImages: frame ", k), frames[k], cameras[k]->describe(), 1);
    plans.emplace_back(scene, *cameras[k], forCamera, frames[k]);
  }
  return renderPlans(plans, progress, start);
}

std::vector<RenderStats> renderImagesStacked(const Scene& scene,
                                             const std::vector<const Camera*>& cameras,
                                             const RenderSettings& settings, Framebuffer& stacked,
                                             const std::function<void(size_t)>& progress) {
  return renderImagesStacked(scene, cameras, settings, framePixelsOf(stacked), progress);
}

std::vector<RenderStats> renderImagesStacked(const Scene& scene,
                                             const std::vector<const Camera*>& cameras,
                                             const RenderSettings& settings,
                                             const FramePixels& stacked,
                                             const std::function<void(size_t)>& progress) {
  const TimePoint start = std::chrono::steady_clock::now();
  validateRenderSettings(settings);
  if (cameras.empty()) throw Error("renderImagesStacked: no camera");
  const CameraDescription first = cameras.front()->describe();
  checkFrameStorage("renderImagesStacked", stacked, first, cameras.size());
  const size_t framePixels = size_t(first.width) * size_t(first.height);
  std::deque<ImagePlan> plans;
  for (size_t k = 0; k < cameras.size(); ++k) {
    APERTURE_CHECK_OP(cameras[k], !=, nullptr);
    const CameraDescription d = cameras[k]->describe();
    if (d.width != first.width || d.height != first.height)
      throw Error(cat("renderImagesStacked: camera ", k, " is ", d.width, "x", d.height,
                      ", camera 0 is ", first.width, "x", first.height,
                      ": stacked frames share one size"));
    plans.emplace_back(scene, *cameras[k], settingsFor(*cameras[k], settings), stacked,
                       k * framePixels);
  }
  return renderPlans(plans, progress, start);
}

}  // namespace aperture
