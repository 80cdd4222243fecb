#include "core/framebuffer.h"

#include <limits>
#include <sstream>

#include "core/error.h"

namespace aperture {

namespace {
struct AovName {
  const char* name;
  Aov bit;
};
constexpr AovName kAovNames[] = {
    {"color", kAovColor},   {"depth", kAovDepth},       {"distance", kAovDistance},
    {"normal", kAovNormal}, {"position", kAovPosition}, {"primid", kAovPrimId},
    {"geomid", kAovGeomId},
};
}  // namespace

AovMask parseAovList(const std::string& list) {
  AovMask mask = 0;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    if (item == "all") {
      for (const auto& a : kAovNames) mask |= a.bit;
      continue;
    }
    bool found = false;
    for (const auto& a : kAovNames)
      if (item == a.name) mask |= a.bit, found = true;
    if (!found) {
      std::string known;
      for (const auto& a : kAovNames) known += std::string(known.empty() ? "" : ", ") + a.name;
      throw Error(cat("unknown AOV '", item, "' (known: ", known, ", all)"));
    }
  }
  if (mask == 0) throw Error(cat("empty AOV list '", list, "'"));
  return mask;
}

std::string aovListString(AovMask mask) {
  std::string s;
  for (const auto& a : kAovNames)
    if (mask & a.bit) s += std::string(s.empty() ? "" : ",") + a.name;
  return s;
}

Framebuffer::Framebuffer(int w, int h, AovMask mask) : width(w), height(h), aovs(mask) {
  const size_t n = pixelCount();
  const float inf = std::numeric_limits<float>::infinity();
  if (mask & kAovColor) rgba.assign(4 * n, 0.0f);
  if (mask & kAovDepth) depth.assign(n, inf);
  if (mask & kAovDistance) distance.assign(n, inf);
  if (mask & kAovNormal) normal.assign(3 * n, 0.0f);
  if (mask & kAovPosition) position.assign(3 * n, 0.0f);
  if (mask & kAovPrimId) primId.assign(n, kInvalidId);
  if (mask & kAovGeomId) geomId.assign(n, kInvalidId);
}

}  // namespace aperture
