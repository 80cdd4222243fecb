#pragma once
// Layered hits (--layers K): the first K surfaces along each pixel-centre ray, found either by
// Embree's intersection filter (one traversal) or by re-tracing past the previous hit.
#include <glm/glm.hpp>
#include <string>

#include "core/aov/frame_pixels.h"
#include "core/aov/framebuffer.h"
#include "core/engine/camera.h"
#include "core/engine/packet.h"
#include "core/engine/scene.h"

namespace aperture {

/// The largest --layers K.
inline constexpr int kMaxLayers = 64;

/// How the layers after the first are found.
///  - Filter: one more traversal whose context filter function sees every hit along the ray,
///    keeps the K nearest per lane (ties in t ordered by object, then primID) and rejects
///    them so traversal goes on; once a lane holds K hits, the K-th is accepted so Embree
///    stops looking beyond it. Exact: coincident surfaces are all reported. A primitive
///    reported twice (Embree may test a triangle in several leaves) counts once.
///  - Retrace: after each hit, the lanes still short of K are traced again with tnear moved
///    to the next float after the hit's t (std::nextafter, no relative epsilon: t has the
///    same parametrisation in every pass, so nothing farther than one ulp is skipped). Lost:
///    surfaces at exactly the same float t as the previous hit (coincident triangles, or the
///    second triangle of a shared edge), which Filter reports as separate layers.
enum class LayerMethod { Filter, Retrace };
LayerMethod parseLayerMethod(const std::string& name);  ///< filter|retrace, else Error
const char* layerMethodName(LayerMethod method);
/// The method renders use: the last setLayerMethod, else APERTURE_LAYERS_METHOD
/// (filter|retrace) when set, read once per process (an unknown name is an Error on first
/// use), else Filter. An internal switch for measuring the two (bench/layers_methods.sh, the
/// bench's hidden --layers-method) and for tests, not a user setting.
LayerMethod defaultLayerMethod();
/// Overrides defaultLayerMethod for the rest of the process (not during a render).
void setLayerMethod(LayerMethod method);

/// Throws Error unless 1 <= layers <= kMaxLayers; `source` names where the value came from
/// ("--layers", "job.json: layers").
void checkLayerCount(int layers, const char* source);

/// Whether a scene rendered with `aovs` should be built with BuildOptions::contextFilter: when
/// layers are asked for and the default method is Filter.
bool layersNeedContextFilter(const AovSet& aovs);

/// One surface along a ray: Embree's t, its unnormalised geometric normal (in the space of
/// the object's mesh, as Embree reports it) and raw ids (instID: RTC_INVALID_GEOMETRY_ID when
/// the mesh is attached directly; chunk hits already resolved to their object).
struct LayerHit {
  float t;
  glm::vec3 ng;
  unsigned primID, geomID, instID;

  bool samePrimitive(const LayerHit& o) const {
    return primID == o.primID && geomID == o.geomID && instID == o.instID;
  }
  /// The object the Z/T/geomID AOVs name: the instance, or the directly attached geometry.
  unsigned object() const { return instID == RTC_INVALID_GEOMETRY_ID ? geomID : instID; }
  /// Order along the ray: t, then object and primID, so ties come out the same at every
  /// packet width whatever order Embree visits them in.
  bool before(const LayerHit& o) const {
    if (t != o.t) return t < o.t;
    if (object() != o.object()) return object() < o.object();
    return primID < o.primID;
  }
};

/// The surfaces of one ray, nearest first, at most kMaxLayers.
struct LaneLayers {
  LayerHit hit[kMaxLayers];
  int count = 0;

  void push(const LayerHit& h) { hit[count++] = h; }
  bool contains(const LayerHit& h) const {
    for (int i = 0; i < count; ++i)
      if (hit[i].samePrimitive(h)) return true;
    return false;
  }
  /// Inserts `h` in order, keeping the `capacity` nearest. Returns the index it went to, or
  /// -1 when it was not kept (a duplicate, or beyond the nearest `capacity`).
  int insert(const LayerHit& h, int capacity) {
    if (contains(h)) return -1;
    if (count == capacity && !h.before(hit[count - 1])) return -1;
    int i = count < capacity ? count++ : capacity - 1;
    for (; i > 0 && h.before(hit[i - 1]); --i) hit[i] = hit[i - 1];
    hit[i] = h;
    return i;
  }
};

/// What traceSurfaces looks for along each ray.
struct SurfaceSearch {
  int surfaces = 1;  ///< K: the first K surfaces (1..kMaxLayers)
  /// How far (in t) past a surface the next one may begin. 0: every primitive along the ray is
  /// a surface (--layers). Above 0 (a LiDAR's returns): the surfaces are the chain t0 < t1 <
  /// ... with t0 the nearest hit and t(k+1) the nearest hit at or past max(nextafter(tk),
  /// tk + separation), so the two triangles of an edge, or coincident ones, are one surface.
  float separation = 0;
  /// Filter falls back to Retrace on a scene built without BuildOptions::contextFilter.
  LayerMethod method = LayerMethod::Filter;
};

/// The surfaces along the valid lanes of `rays` (filled by the caller: render-space origins,
/// directions, [tnear, tfar], time, mask; valid −1/0). found[k] gets lane k's, nearest first.
/// `first`: the lanes' closest hits when the caller traced them already (Retrace starts from
/// them), else nullptr. The lanes' ids and hits are overwritten; their rays are left as given
/// except tnear (Retrace moves it on). With separation 0 and Filter, found[k] is the K nearest
/// primitives (ties in t ordered as LayerHit::before, coincident ones all reported); Retrace
/// loses surfaces at the same float t as the one before (see LayerMethod). With a separation,
/// both give the chain above (Filter: one traversal collecting the 2K nearest primitives, and
/// another from past the last of them while the chain is short of K and more may lie beyond).
template <int N>
void traceSurfaces(const Scene& scene, const SurfaceSearch& search, PacketBuffers<N>& rays,
                   const LayerHit* first, LaneLayers* found);

extern template void traceSurfaces<1>(const Scene&, const SurfaceSearch&, PacketBuffers<1>&,
                                      const LayerHit*, LaneLayers*);
extern template void traceSurfaces<4>(const Scene&, const SurfaceSearch&, PacketBuffers<4>&,
                                      const LayerHit*, LaneLayers*);
extern template void traceSurfaces<8>(const Scene&, const SurfaceSearch&, PacketBuffers<8>&,
                                      const LayerHit*, LaneLayers*);
extern template void traceSurfaces<16>(const Scene&, const SurfaceSearch&, PacketBuffers<16>&,
                                       const LayerHit*, LaneLayers*);

/// What layer tracing needs of one frame.
struct LayerPlan {
  /// `eye` and `axis`: the camera's render-space eye and view axis (planar depth, as the Z
  /// AOV). The method falls back to Retrace on a scene built without contextFilter.
  /// `px`: the storage of the layered hits ("layers.depth", ...), which must hold them.
  LayerPlan(const Scene& scene, const Camera& camera, const FramePixels& px, glm::vec3 eye,
            glm::vec3 axis, LayerMethod method = defaultLayerMethod());
  /// The layers of `fb` (framePixelsOf).
  LayerPlan(const Scene& scene, const Camera& camera, Framebuffer& fb, glm::vec3 eye,
            glm::vec3 axis, LayerMethod method = defaultLayerMethod());

  const Scene& scene;
  const Camera& camera;
  /// Where layer k of storage pixel p goes: [k · pixelCount + p] of each.
  float *depth, *distance;
  uint32_t *primId, *geomId;
  size_t pixelCount;  ///< pixels of the storage (all its stacked frames)
  glm::vec3 eye, axis;
  LayerMethod method;      ///< the method actually used
  int layers;              ///< K = AovSet::layers of the storage
  int imageWidth;          ///< the camera's image width (the storage's unless frames are stacked)
  size_t pixelOffset = 0;  ///< storage index of the image's pixel (0, 0)
  /// Places the image in a framebuffer of stacked frames (core/engine/render.h
  /// renderImagesStacked).
  void place(int width, size_t offset) { imageWidth = width, pixelOffset = offset; }
};

/// Fills the plan's layers at the pixels of the packet of `req` (a centre-ray request) from its
/// traced first hits: `first` the packet's hit fields after rtcIntersectN, `hit[k]` nonzero
/// for lanes that hit. Layer 0 is that first hit itself (so it equals the Z, T, primID and
/// geomID AOVs bit for bit); layers 1..K-1 are the next surfaces in t order. Lanes that did
/// not hit, and layers past the last surface, keep the storage's miss values. The rays are
/// generated again from the camera (deterministic), so the caller's packet is not touched.
template <int N>
void traceLayers(const LayerPlan& plan, const PacketRequest& req, const HitLanes& first,
                 const int* hit);

extern template void traceLayers<1>(const LayerPlan&, const PacketRequest&, const HitLanes&,
                                    const int*);
extern template void traceLayers<4>(const LayerPlan&, const PacketRequest&, const HitLanes&,
                                    const int*);
extern template void traceLayers<8>(const LayerPlan&, const PacketRequest&, const HitLanes&,
                                    const int*);
extern template void traceLayers<16>(const LayerPlan&, const PacketRequest&, const HitLanes&,
                                     const int*);

}  // namespace aperture
