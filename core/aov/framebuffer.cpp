#include "core/aov/framebuffer.h"

#include <iterator>
#include <limits>
#include <sstream>

#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {
struct AovName {
  const char* name;
  Aov bit;
  bool inAll;  ///< part of "all" (shading-normal is asked for by name)
};
constexpr AovName kAovNames[] = {
    {"color", kAovColor, true},       {"depth", kAovDepth, true},
    {"distance", kAovDistance, true}, {"normal", kAovNormal, true},
    {"position", kAovPosition, true}, {"primid", kAovPrimId, true},
    {"geomid", kAovGeomId, true},     {"shading-normal", kAovShadingNormal, false},
};
constexpr const char* kFacePrefix = "face.";
constexpr const char* kVertexPrefix = "vertex.";

std::vector<std::string> knownAovNames() {
  std::vector<std::string> names;
  for (const auto& a : kAovNames) names.emplace_back(a.name);
  names.emplace_back("all");
  return names;
}

bool startsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

/// "face.NAME" / "vertex.NAME" as a property, or false when `item` is neither.
bool parsePropertyAov(const std::string& item, PropertyAov& out) {
  for (const auto& [prefix, domain] : {std::pair{kFacePrefix, PropertyDomain::Face},
                                       std::pair{kVertexPrefix, PropertyDomain::Vertex}}) {
    if (!startsWith(item, prefix)) continue;
    out.domain = domain;
    out.name = item.substr(std::string(prefix).size());
    if (out.name.empty())
      throw Error(cat("AOV '", item, "' names no property (e.g. ", prefix, "object_id)"));
    return true;
  }
  return false;
}

AovMask fixedAov(const std::string& item) {
  if (item == "all") {
    AovMask mask = 0;
    for (const auto& a : kAovNames)
      if (a.inAll) mask |= a.bit;
    return mask;
  }
  for (const auto& a : kAovNames)
    if (item == a.name) return a.bit;
  const std::vector<std::string> known = knownAovNames();
  throw Error(cat("unknown AOV '", item, "'", didYouMean(item, known),
                  " (known: ", join(known, ", "), ", face.NAME, vertex.NAME)"));
}
}  // namespace

std::string PropertyAov::aovName() const {
  return (domain == PropertyDomain::Face ? kFacePrefix : kVertexPrefix) + name;
}

AovSet parseAovSet(const std::string& list) {
  AovSet set;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    PropertyAov property;
    if (parsePropertyAov(item, property)) {
      bool seen = false;
      for (const PropertyAov& p : set.properties) seen = seen || p == property;
      if (!seen) set.properties.push_back(property);
      continue;
    }
    set.mask |= fixedAov(item);
  }
  if (set.empty()) throw Error(cat("empty AOV list '", list, "'"));
  return set;
}

AovMask parseAovList(const std::string& list) {
  const AovSet set = parseAovSet(list);
  if (!set.properties.empty())
    throw Error(cat("AOV '", set.properties.front().aovName(),
                    "' (a mesh property) is not available here"));
  return set.mask;
}

std::string aovListString(const AovSet& set) {
  std::string s;
  for (const auto& a : kAovNames)
    if (set.mask & a.bit) s += std::string(s.empty() ? "" : ",") + a.name;
  for (const PropertyAov& p : set.properties) s += std::string(s.empty() ? "" : ",") + p.aovName();
  return s;
}

Framebuffer::Framebuffer(int w, int h, const AovSet& set)
    : width(w), height(h), aovs(set.mask), layers(set.layers) {
  const size_t n = pixelCount();
  const float inf = std::numeric_limits<float>::infinity();
  const AovMask mask = set.mask;
  if (mask & kAovColor) rgba.assign(4 * n, 0.0f);
  if (mask & kAovDepth) depth.assign(n, inf);
  if (mask & kAovDistance) distance.assign(n, inf);
  if (mask & kAovNormal) normal.assign(3 * n, 0.0f);
  if (mask & kAovPosition) position.assign(3 * n, 0.0f);
  if (mask & kAovPrimId) primId.assign(n, kInvalidId);
  if (mask & kAovGeomId) geomId.assign(n, kInvalidId);
  if (mask & kAovShadingNormal) shadingNormal.assign(3 * n, 0.0f);
  for (const PropertyAov& p : set.properties)
    properties.push_back({p, std::vector<uint32_t>(n, kInvalidId)});
  if (layers > 0) {
    const size_t ln = size_t(layers) * n;
    layerDepth.assign(ln, inf);
    layerDistance.assign(ln, inf);
    layerPrimId.assign(ln, kInvalidId);
    layerGeomId.assign(ln, kInvalidId);
  }
}

AovSet Framebuffer::aovSet() const {
  AovSet set(aovs);
  for (const PropertyChannel& c : properties) set.properties.push_back(c.property);
  set.layers = layers;
  return set;
}

namespace {
ImageView floatView(const Framebuffer& fb, const std::vector<float>& v, int channels) {
  return {fb.width, fb.height, channels, v.data(), nullptr};
}
ImageView uintView(const Framebuffer& fb, const std::vector<uint32_t>& v) {
  return {fb.width, fb.height, 1, nullptr, v.data()};
}

/// The layered-hit views by name ("layers.depth", ...), in the order aovNames lists them.
constexpr const char* kLayerViewNames[] = {"layers.depth", "layers.distance", "layers.primid",
                                           "layers.geomid"};

ImageView layerView(const Framebuffer& fb, int which) {
  ImageView v{fb.width, fb.height, 1, nullptr, nullptr, fb.layers};
  switch (which) {
    case 0:
      v.f32 = fb.layerDepth.data();
      break;
    case 1:
      v.f32 = fb.layerDistance.data();
      break;
    case 2:
      v.u32 = fb.layerPrimId.data();
      break;
    default:
      v.u32 = fb.layerGeomId.data();
  }
  return v;
}
}  // namespace

ImageView aovView(const Framebuffer& fb, const std::string& aovName) {
  if (fb.layers > 0)
    for (int k = 0; k < 4; ++k)
      if (aovName == kLayerViewNames[k]) return layerView(fb, k);
  PropertyAov property;
  if (parsePropertyAov(aovName, property)) {
    for (const PropertyChannel& c : fb.properties)
      if (c.property == property) return uintView(fb, c.values);
  } else {
    for (const auto& a : kAovNames) {
      if (aovName != a.name || !fb.has(a.bit)) continue;
      switch (a.bit) {
        case kAovColor:
          return floatView(fb, fb.rgba, 4);
        case kAovDepth:
          return floatView(fb, fb.depth, 1);
        case kAovDistance:
          return floatView(fb, fb.distance, 1);
        case kAovNormal:
          return floatView(fb, fb.normal, 3);
        case kAovPosition:
          return floatView(fb, fb.position, 3);
        case kAovPrimId:
          return uintView(fb, fb.primId);
        case kAovGeomId:
          return uintView(fb, fb.geomId);
        case kAovShadingNormal:
          return floatView(fb, fb.shadingNormal, 3);
      }
    }
  }
  throw Error(
      cat("AOV '", aovName, "' was not rendered (this frame has: ", join(aovNames(fb), ", "), ")"));
}

std::vector<std::string> aovNames(const Framebuffer& fb) {
  std::vector<std::string> names;
  for (const auto& a : kAovNames)
    if (fb.has(a.bit)) names.emplace_back(a.name);
  for (const PropertyChannel& c : fb.properties) names.push_back(c.property.aovName());
  if (fb.layers > 0)
    names.insert(names.end(), std::begin(kLayerViewNames), std::end(kLayerViewNames));
  return names;
}

}  // namespace aperture
