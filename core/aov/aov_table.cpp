#include "core/aov/aov_table.h"

#include <algorithm>
#include <functional>
#include <limits>

#include "core/util/error.h"

namespace aperture {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kIdMiss = double(kInvalidId);

AovRow floatRow(const char* name, AovMask bit, std::vector<std::string> channels, double miss,
                std::vector<float> Framebuffer::*pixels, const char* meaning) {
  AovRow row;
  row.name = name, row.bit = bit, row.type = AovType::Float32;
  row.exrChannels = std::move(channels), row.miss = miss, row.f32 = pixels, row.meaning = meaning;
  return row;
}

AovRow uintRow(const char* name, AovMask bit, const char* channel,
               std::vector<uint32_t> Framebuffer::*pixels, const char* meaning) {
  AovRow row;
  row.name = name, row.bit = bit, row.type = AovType::UInt32;
  row.exrChannels = {channel}, row.miss = kIdMiss, row.u32 = pixels, row.meaning = meaning;
  return row;
}

std::vector<AovRow> fixedRows() {
  using F = Framebuffer;
  std::vector<AovRow> rows = {
      floatRow("color", kAovColor, {"R", "G", "B", "A"}, 0.0, &F::rgba,
               "eye-light \\|N·D\\|, linear; A = coverage"),
      floatRow("depth", kAovDepth, {"Z"}, kInf, &F::depth, "planar depth along the view axis"),
      floatRow("distance", kAovDistance, {"T"}, kInf, &F::distance,
               "distance from the ray origin to the hit"),
      floatRow("normal", kAovNormal, {"N.X", "N.Y", "N.Z"}, 0.0, &F::normal,
               "unit geometric normal, world space or `--normal-frame`"),
      floatRow("position", kAovPosition, {"P.X", "P.Y", "P.Z"}, 0.0, &F::position, "world space"),
      uintRow("primid", kAovPrimId, "primID", &F::primId,
              "the mesh's triangle index (after triangulation)"),
      uintRow("geomid", kAovGeomId, "geomID", &F::geomId, "the object (mesh placement)"),
      floatRow("shading-normal", kAovShadingNormal, {"Ns.X", "Ns.Y", "Ns.Z"}, 0.0,
               &F::shadingNormal,
               "unit interpolated vertex normal (the geometric normal without vertex normals), "
               "world space or `--normal-frame`"),
      uintRow("instance", kAovInstanceId, "instanceID", &F::instanceId,
              "the object's instance id (glTF node, OBJ object; `ObjectIds`)"),
      uintRow("mesh", kAovMeshId, "meshID", &F::meshId, "the object's mesh id (glTF mesh)"),
      uintRow("material", kAovMaterialId, "materialID", &F::materialId,
              "the material of the triangle shown (scene-wide id)"),
      floatRow("barycentric", kAovBarycentric, {"bary.U", "bary.V"}, 0.0, &F::barycentric,
               "Embree's u, v: the weights of the triangle's 2nd and 3rd vertex (index order)"),
      floatRow("uv", kAovUv, {"uv.U", "uv.V"}, 0.0, &F::uv,
               "texture coordinates interpolated (0 on a mesh without them)"),
      floatRow("vertex-color", kAovVertexColor, {"Cd.R", "Cd.G", "Cd.B", "Cd.A"}, 0.0,
               &F::vertexColor,
               "vertex colour interpolated, linear RGBA (1 on a mesh without colours)"),
      floatRow("albedo", kAovAlbedo, {"albedo.R", "albedo.G", "albedo.B", "albedo.A"}, 0.0,
               &F::albedo,
               "unlit base colour × texture × vertex colour, linear RGBA (docs/aovs.md)"),
  };
  auto row = [&](const char* name) -> AovRow& {
    for (AovRow& r : rows)
      if (r.name == name) return r;
    throw Error(cat("no fixed AOV '", name, "'"));
  };
  // The layered hits (--layers K): layer 0 is the first surface, equal to these AOVs.
  row("depth").layerF32 = &F::layerDepth;
  row("distance").layerF32 = &F::layerDistance;
  row("primid").layerU32 = &F::layerPrimId;
  row("geomid").layerU32 = &F::layerGeomId;
  row("color").absentFill = {0, 0, 0, 1};  // an EXR without A is opaque
  row("color").halfInExr = true;
  row("shading-normal").inAll = false;  // asked for by name: it loads the vertex normals
  // Asked for by name: they read what a scene file's loader keeps only when asked (texture
  // coordinates, colours, materials, groups), and "all" keeps its outputs.
  for (const char* name :
       {"instance", "mesh", "material", "barycentric", "uv", "vertex-color", "albedo"})
    row(name).inAll = false;
  // Previews show the first of these that was rendered, in table order.
  row("color").preview = PreviewRule::Color;
  row("depth").preview = PreviewRule::Grey;
  row("normal").preview = PreviewRule::Normal;
  row("primid").preview = PreviewRule::HashedId;
  row("geomid").preview = PreviewRule::HashedId;
  row("instance").preview = PreviewRule::HashedId;
  row("mesh").preview = PreviewRule::HashedId;
  row("material").preview = PreviewRule::HashedId;
  row("albedo").preview = PreviewRule::Color;
  row("albedo").previewFirst = true;  // asked for, the unlit colours are the picture
  return rows;
}

std::vector<AovRow>& table() {
  static std::vector<AovRow> rows = fixedRows();
  return rows;
}

/// "0", "+inf", "0xFFFFFFFF": a miss value as the docs write it.
std::string missText(const AovRow& row) {
  if (!row.isFloat()) return row.miss == kIdMiss ? "0xFFFFFFFF" : cat(uint64_t(row.miss));
  if (row.miss == kInf) return "+inf";
  return cat(row.miss);
}

}  // namespace

const std::vector<AovRow>& aovTable() { return table(); }

const AovRow* findAovRow(const std::string& name) {
  for (const AovRow& row : table())
    if (row.name == name) return &row;
  return nullptr;
}

namespace {
template <typename T>
std::vector<T>* pixelsOf(const Framebuffer& fb, const AovRow& row,
                         std::vector<T> Framebuffer::*member,
                         std::vector<T> Framebuffer::RegisteredPixels::*registered) {
  auto& f = const_cast<Framebuffer&>(fb);
  if (member) return &(f.*member);
  for (Framebuffer::RegisteredPixels& r : f.registered)
    if (r.bit == row.bit) return &(r.*registered);
  return nullptr;
}
}  // namespace

std::vector<float>& floatPixels(Framebuffer& fb, const AovRow& row) {
  std::vector<float>* p = pixelsOf(fb, row, row.f32, &Framebuffer::RegisteredPixels::f32);
  if (!p) throw Error(cat("the framebuffer does not hold AOV '", row.name, "'"));
  return *p;
}

std::vector<uint32_t>& uintPixels(Framebuffer& fb, const AovRow& row) {
  std::vector<uint32_t>* p = pixelsOf(fb, row, row.u32, &Framebuffer::RegisteredPixels::u32);
  if (!p) throw Error(cat("the framebuffer does not hold AOV '", row.name, "'"));
  return *p;
}

const std::vector<float>& floatPixels(const Framebuffer& fb, const AovRow& row) {
  static const std::vector<float> none;
  const std::vector<float>* p = pixelsOf(fb, row, row.f32, &Framebuffer::RegisteredPixels::f32);
  return p ? *p : none;
}

const std::vector<uint32_t>& uintPixels(const Framebuffer& fb, const AovRow& row) {
  static const std::vector<uint32_t> none;
  const std::vector<uint32_t>* p = pixelsOf(fb, row, row.u32, &Framebuffer::RegisteredPixels::u32);
  return p ? *p : none;
}

const std::vector<float>& layerFloatPixels(const Framebuffer& fb, const AovRow& row) {
  if (!row.layerF32) throw Error(cat("AOV '", row.name, "' has no float layers"));
  return fb.*row.layerF32;
}

const std::vector<uint32_t>& layerUintPixels(const Framebuffer& fb, const AovRow& row) {
  if (!row.layerU32) throw Error(cat("AOV '", row.name, "' has no uint32 layers"));
  return fb.*row.layerU32;
}

namespace {
constexpr const char* kLayerAovPrefix = "layers.";
}  // namespace

std::string layerAovName(const AovRow& row) { return kLayerAovPrefix + row.name; }

bool isLayerAovName(const std::string& aovName) { return aovName.rfind(kLayerAovPrefix, 0) == 0; }

std::string layerChannelName(int layer, const AovRow& row) {
  return cat("hit", layer, ".", row.exrChannels.front());
}

size_t valueCount(const Framebuffer& fb, const AovRow& row) {
  return row.isFloat() ? floatPixels(fb, row).size() : uintPixels(fb, row).size();
}

AovRegistration::AovRegistration(AovRow row) {
  AovMask used = 0;
  for (const AovRow& r : table()) {
    used |= r.bit;
    if (r.name == row.name) throw Error(cat("AOV '", row.name, "' is already in the table"));
    for (const std::string& c : row.exrChannels)
      if (std::find(r.exrChannels.begin(), r.exrChannels.end(), c) != r.exrChannels.end())
        throw Error(cat("AOV '", row.name, "': EXR channel '", c, "' is AOV '", r.name, "''s"));
  }
  if (row.exrChannels.empty()) throw Error(cat("AOV '", row.name, "' has no channel"));
  if (row.f32 || row.u32 || row.layered())
    throw Error(cat("AOV '", row.name, "': a registered row keeps its pixels in the framebuffer"));
  for (int b = 0; b < 32 && bit_ == 0; ++b)
    if ((used & (1u << b)) == 0) bit_ = 1u << b;
  if (bit_ == 0) throw Error(cat("AOV '", row.name, "': all 32 AOV bits are taken"));
  row.bit = bit_;
  table().push_back(std::move(row));
}

AovRegistration::~AovRegistration() {
  std::vector<AovRow>& rows = table();
  rows.erase(std::remove_if(rows.begin(), rows.end(),
                            [&](const AovRow& r) { return r.bit == bit_ && !r.f32 && !r.u32; }),
             rows.end());
}

std::string aovNameList() {
  std::vector<std::string> names;
  for (const AovRow& row : table())
    if (row.inAll) names.push_back(row.name);
  names.emplace_back("all");
  for (const AovRow& row : table())
    if (!row.inAll) names.push_back(row.name);
  return join(names, ", ");
}

std::string exrChannelSummary() {
  std::vector<std::string> parts;
  for (const AovRow& row : table()) {
    // "N.*" for channels that share a layer prefix, else the names.
    const std::string& first = row.exrChannels.front();
    const size_t dot = first.find('.');
    bool layer = row.channels() > 1 && dot != std::string::npos;
    for (const std::string& c : row.exrChannels)
      layer = layer && c.compare(0, dot + 1, first, 0, dot + 1) == 0;
    parts.push_back(layer ? first.substr(0, dot) + ".*" : join(row.exrChannels, " "));
  }
  return join(parts, ", ");
}

std::string aovNamesWhere(const std::function<bool(int channels, bool isFloat)>& holds) {
  std::vector<std::string> names;
  for (const AovRow& row : table())
    if (holds(row.channels(), row.isFloat())) names.push_back(row.name);
  return join(names, ", ");
}

std::string aovMarkdownTable() {
  std::string md =
      "| AOV | channels | type | frame | miss |\n"
      "|---|---|---|---|---|\n";
  for (const AovRow& row : table()) {
    const std::string type = std::string(row.isFloat() ? "float32" : "uint32") +
                             (row.halfInExr ? " (half with `--half`)" : "");
    md += cat("| `", row.name, "` | `", join(row.exrChannels, " "), "` | ", type, " | ",
              row.meaning, " | ", missText(row), " |\n");
  }
  const std::pair<PropertyDomain, const char*> properties[] = {
      {PropertyDomain::Face, "the integer face property NAME of the face shown"},
      {PropertyDomain::Vertex,
       "the integer vertex property NAME of the hit triangle's nearest vertex"}};
  for (const auto& [domain, meaning] : properties) {
    const std::string name = PropertyAov{domain, "NAME"}.aovName();
    md += cat("| `", name, "` | `", name, "` | uint32 | ", meaning, " | 0xFFFFFFFF |\n");
  }
  return md;
}

}  // namespace aperture
