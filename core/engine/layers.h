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
void checkLayerCount(int layers, const std::string& source);

/// Whether a scene rendered with `aovs` should be built with BuildOptions::contextFilter: when
/// layers are asked for and the default method is Filter.
bool layersNeedContextFilter(const AovSet& aovs);

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
