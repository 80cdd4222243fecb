#include "core/aov/framebuffer.h"

#include <iterator>
#include <limits>
#include <sstream>

#include "core/aov/aov_table.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {
constexpr const char* kFacePrefix = "face.";
constexpr const char* kVertexPrefix = "vertex.";

std::vector<std::string> knownAovNames() {
  std::vector<std::string> names;
  for (const AovRow& row : aovTable()) names.push_back(row.name);
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
    for (const AovRow& row : aovTable())
      if (row.inAll) mask |= row.bit;
    return mask;
  }
  if (const AovRow* row = findAovRow(item)) return row->bit;
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
  for (const AovRow& row : aovTable())
    if (set.mask & row.bit) s += std::string(s.empty() ? "" : ",") + row.name;
  for (const PropertyAov& p : set.properties) s += std::string(s.empty() ? "" : ",") + p.aovName();
  return s;
}

Framebuffer::Framebuffer(int w, int h, const AovSet& set)
    : width(w), height(h), aovs(set.mask), layers(set.layers) {
  const size_t n = pixelCount();
  for (const AovRow& row : aovTable()) {
    if ((set.mask & row.bit) == 0) continue;
    if (!row.f32 && !row.u32) registered.push_back({row.bit, {}, {}});
    const size_t values = size_t(row.channels()) * n;
    if (row.isFloat())
      floatPixels(*this, row).assign(values, float(row.miss));
    else
      uintPixels(*this, row).assign(values, uint32_t(row.miss));
  }
  for (const PropertyAov& p : set.properties)
    properties.push_back({p, std::vector<uint32_t>(n, kInvalidId)});
  if (layers > 0)
    for (const AovRow& row : aovTable()) {
      const size_t ln = size_t(layers) * n;
      if (row.layerF32) (this->*row.layerF32).assign(ln, float(row.miss));
      if (row.layerU32) (this->*row.layerU32).assign(ln, uint32_t(row.miss));
    }
}

AovSet Framebuffer::aovSet() const {
  AovSet set(aovs);
  for (const PropertyChannel& c : properties) set.properties.push_back(c.property);
  set.layers = layers;
  return set;
}

namespace {
ImageView viewOf(const Framebuffer& fb, const AovRow& row) {
  ImageView v{fb.width, fb.height, row.channels(), nullptr, nullptr};
  if (row.isFloat())
    v.f32 = floatPixels(fb, row).data();
  else
    v.u32 = uintPixels(fb, row).data();
  return v;
}
ImageView uintView(const Framebuffer& fb, const std::vector<uint32_t>& v) {
  return {fb.width, fb.height, 1, nullptr, v.data()};
}

/// The view of a layered row's hits ("layers.depth", ...).
ImageView layerView(const Framebuffer& fb, const AovRow& row) {
  ImageView v{fb.width, fb.height, 1, nullptr, nullptr, fb.layers};
  if (row.layerF32)
    v.f32 = layerFloatPixels(fb, row).data();
  else
    v.u32 = layerUintPixels(fb, row).data();
  return v;
}
}  // namespace

ImageView aovView(const Framebuffer& fb, const std::string& aovName) {
  if (fb.layers > 0)
    for (const AovRow& row : aovTable())
      if (row.layered() && aovName == layerAovName(row)) return layerView(fb, row);
  PropertyAov property;
  if (parsePropertyAov(aovName, property)) {
    for (const PropertyChannel& c : fb.properties)
      if (c.property == property) return uintView(fb, c.values);
  } else if (const AovRow* row = findAovRow(aovName); row && fb.has(Aov(row->bit))) {
    return viewOf(fb, *row);
  }
  throw Error(
      cat("AOV '", aovName, "' was not rendered (this frame has: ", join(aovNames(fb), ", "), ")"));
}

std::vector<std::string> aovNames(const Framebuffer& fb) {
  std::vector<std::string> names;
  for (const AovRow& row : aovTable())
    if (fb.has(Aov(row.bit))) names.push_back(row.name);
  for (const PropertyChannel& c : fb.properties) names.push_back(c.property.aovName());
  if (fb.layers > 0)
    for (const AovRow& row : aovTable())
      if (row.layered()) names.push_back(layerAovName(row));
  return names;
}

}  // namespace aperture
