#pragma once
// AOV (arbitrary output variable) framebuffers. Only requested AOVs are allocated.
#include <cstdint>
#include <string>
#include <vector>

namespace aperture {

/// One bit per fixed AOV; a frame computes and stores only the bits it is asked for.
enum Aov : uint32_t {
  kAovColor = 1u << 0,     ///< R G B A: eye-light |N·D| shading, linear; A = coverage
  kAovDepth = 1u << 1,     ///< Z: planar depth along the view axis, scene units
  kAovDistance = 1u << 2,  ///< T: distance from the ray origin to the hit, scene units
  kAovNormal = 1u << 3,    ///< N.X N.Y N.Z: unit geometric normal (RenderSettings::normalFrame)
  kAovPosition = 1u << 4,  ///< P.X P.Y P.Z: hit point, world space
  kAovPrimId = 1u << 5,    ///< primID (UINT)
  kAovGeomId = 1u << 6,    ///< geomID (UINT)
  kAovShadingNormal = 1u << 7,  ///< Ns.X Ns.Y Ns.Z: interpolated vertex normal, unit length
  kAovInstanceId = 1u << 8,     ///< instance id (UINT; ObjectIds, core/engine/scene.h)
  kAovMeshId = 1u << 9,         ///< mesh id (UINT)
  kAovMaterialId = 1u << 10,    ///< material id (UINT)
  kAovBarycentric = 1u << 11,   ///< Embree's u, v of the hit (index-buffer vertex order)
  kAovUv = 1u << 12,            ///< texture coordinates interpolated (Mesh::texcoords)
  kAovVertexColor = 1u << 13,   ///< vertex colour interpolated, linear RGBA
  kAovAlbedo = 1u << 14,        ///< unlit base colour, linear RGBA (Material, TextureSampler)
};
using AovMask = uint32_t;
inline constexpr uint32_t kInvalidId = 0xFFFFFFFFu;

/// Where an integer mesh property lives: one value per face or per vertex.
enum class PropertyDomain { Face, Vertex };

/// An integer property of the mesh requested as an AOV: "face.NAME" (the value of the face
/// a pixel shows; faces triangulated from one polygon share it) or "vertex.NAME" (the value
/// of the hit triangle's vertex nearest the hit, by barycentric weight). Written as a UINT
/// channel named like the AOV, kInvalidId where nothing was hit.
struct PropertyAov {
  PropertyDomain domain = PropertyDomain::Face;
  std::string name;             ///< the PLY property name ("object_id")
  std::string aovName() const;  ///< "face.object_id"
  bool operator==(const PropertyAov& o) const { return domain == o.domain && name == o.name; }
};

/// Everything a frame is asked to compute: the fixed AOVs, mesh properties and layered hits.
/// Implicitly made from a mask, so callers that only use fixed AOVs keep passing masks.
struct AovSet {
  AovMask mask = 0;
  std::vector<PropertyAov> properties;  ///< in request order, no duplicates
  /// --layers K: the first K surfaces along each pixel-centre ray (K >= 1), 0 for none.
  int layers = 0;

  AovSet() = default;
  AovSet(AovMask m) : mask(m) {}  // NOLINT(google-explicit-constructor): a mask is a set
  bool has(Aov a) const { return (mask & a) != 0; }
  bool empty() const { return mask == 0 && properties.empty() && layers == 0; }
  bool operator==(const AovSet& o) const {
    return mask == o.mask && properties == o.properties && layers == o.layers;
  }
};

/// Parses "color,depth,normal" (fixed names: the rows of aovTable(), or "all" for every row in
/// "all") and "face.NAME" / "vertex.NAME".
/// Throws Error naming the bad name, listing the valid ones and suggesting the nearest.
AovSet parseAovSet(const std::string& list);
/// parseAovSet for callers that accept fixed AOVs only; a property name is an error.
AovMask parseAovList(const std::string& list);
/// The canonical comma-separated list: fixed AOVs in bit order, then the properties.
std::string aovListString(const AovSet& set);

/// One UINT property channel of a framebuffer.
struct PropertyChannel {
  PropertyAov property;
  std::vector<uint32_t> values;  ///< one per pixel, kInvalidId on a miss
};

/// Per-pixel storage for the requested AOVs, row-major, row 0 at the top. Vectors of AOVs not
/// requested stay empty. Multi-channel AOVs are interleaved (rgba: 4 floats a pixel). Each
/// fixed AOV's vector is named by its row of the AOV table (core/aov/aov_table.h).
struct Framebuffer {
  int width = 0, height = 0;
  AovMask aovs = 0;
  std::vector<float> rgba;                  ///< 4 per pixel
  std::vector<float> depth;                 ///< Z, +inf on a miss
  std::vector<float> distance;              ///< T, +inf on a miss
  std::vector<float> normal;                ///< 3 per pixel, 0 on a miss
  std::vector<float> position;              ///< 3 per pixel, 0 on a miss
  std::vector<uint32_t> primId;             ///< kInvalidId on a miss
  std::vector<uint32_t> geomId;             ///< kInvalidId on a miss
  std::vector<float> shadingNormal;         ///< 3 per pixel, 0 on a miss
  std::vector<uint32_t> instanceId;         ///< kInvalidId on a miss
  std::vector<uint32_t> meshId;             ///< kInvalidId on a miss
  std::vector<uint32_t> materialId;         ///< kInvalidId on a miss
  std::vector<float> barycentric;           ///< 2 per pixel (Embree's u, v), 0 on a miss
  std::vector<float> uv;                    ///< 2 per pixel, 0 on a miss
  std::vector<float> vertexColor;           ///< 4 per pixel (linear RGBA), 0 on a miss
  std::vector<float> albedo;                ///< 4 per pixel (linear RGBA), 0 on a miss
  std::vector<PropertyChannel> properties;  ///< in AovSet::properties order
  /// Layered hits, layer-major: value of layer k at pixel p is at [k * pixelCount() + p].
  /// Layer 0 is the first surface (equal to Z, T, primID, geomID). Misses as above.
  int layers = 0;
  std::vector<float> layerDepth, layerDistance;
  std::vector<uint32_t> layerPrimId, layerGeomId;
  /// The pixels of the AOVs registered in the table at run time (AovRegistration,
  /// core/aov/aov_table.h), which have no member of their own: f32 or u32 by the row's type.
  struct RegisteredPixels {
    AovMask bit = 0;
    std::vector<float> f32;
    std::vector<uint32_t> u32;
  };
  std::vector<RegisteredPixels> registered;

  Framebuffer() = default;
  /// Allocates the requested AOVs, filled with their miss values.
  Framebuffer(int w, int h, const AovSet& set);
  size_t pixelCount() const { return size_t(width) * size_t(height); }
  bool has(Aov a) const { return (aovs & a) != 0; }
  /// The AovSet this framebuffer holds.
  AovSet aovSet() const;
};

/// One AOV's pixels: H rows of W pixels of C channels, row 0 at the top, interleaved; exactly
/// one of f32 / u32 is set. Layered hits are `layers` such images one after the other
/// (layer-major: [k][row][column][channel]). Does not own the data.
struct ImageView {
  int width = 0, height = 0, channels = 1;
  const float* f32 = nullptr;
  const uint32_t* u32 = nullptr;
  int layers = 1;
};

/// The view of one AOV of `fb` by its name as parseAovSet spells it ("color" gives the 4
/// RGBA channels, "depth", "normal", "primid", "shading-normal", "face.object_id", ...), or
/// of the layered hits: "layers.depth", "layers.distance" (float), "layers.primid",
/// "layers.geomid" (UINT), each with ImageView::layers = fb.layers.
/// Throws Error when the framebuffer does not hold it.
ImageView aovView(const Framebuffer& fb, const std::string& aovName);
/// The names aovView knows for the AOVs `fb` holds, in aovListString order.
std::vector<std::string> aovNames(const Framebuffer& fb);

}  // namespace aperture
