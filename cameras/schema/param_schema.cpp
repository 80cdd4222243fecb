#include "cameras/schema/param_schema.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/util/error.h"
#include "core/util/number_text.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {

std::string number(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

/// The numeric components of a value (none for text and flags).
std::vector<double> components(const ParamValue& v) {
  if (auto* x = std::get_if<double>(&v)) return {*x};
  if (auto* x = std::get_if<int>(&v)) return {double(*x)};
  if (auto* x = std::get_if<glm::dvec2>(&v)) return {x->x, x->y};
  if (auto* x = std::get_if<glm::dvec3>(&v)) return {x->x, x->y, x->z};
  if (auto* x = std::get_if<glm::ivec2>(&v)) return {double(x->x), double(x->y)};
  if (auto* x = std::get_if<std::vector<double>>(&v)) return *x;
  return {};
}

const char* shapeOf(ParamKind k) {
  switch (k) {
    case ParamKind::Number:
      return "a number";
    case ParamKind::Integer:
      return "a whole number";
    case ParamKind::Vec2:
      return "A,B";
    case ParamKind::Vec3:
      return "X,Y,Z";
    case ParamKind::Size:
      return "W,H or WxH (whole numbers)";
    case ParamKind::Flag:
      return "a flag";
    case ParamKind::Choice:
      return "one word";
    case ParamKind::Numbers:
      return "comma-separated numbers";
  }
  return "";
}

size_t componentCount(const ParamSpec& spec) {
  switch (spec.kind) {
    case ParamKind::Vec2:
    case ParamKind::Size:
      return 2;
    case ParamKind::Vec3:
      return 3;
    case ParamKind::Numbers:
      return spec.count;
    default:
      return 1;
  }
}

/// The numbers of a value's text: "1,2,3", or "640x480" for sizes.
std::vector<double> parseNumberList(const ParamSpec& spec, const std::string& text,
                                    const std::string& source) {
  std::string t = text;
  if (spec.kind == ParamKind::Size && t.find(',') == std::string::npos)
    std::replace(t.begin(), t.end(), 'x', ',');
  return parseNumbers(source, t, componentCount(spec), shapeOf(spec.kind));
}

bool isWhole(double x) { return std::isfinite(x) && x == std::floor(x) && std::abs(x) < 2e9; }

ParamValue valueFromNumbers(const ParamSpec& spec, const std::vector<double>& v,
                            const std::string& text, const std::string& source) {
  switch (spec.kind) {
    case ParamKind::Number:
      return v[0];
    case ParamKind::Vec2:
      return glm::dvec2(v[0], v[1]);
    case ParamKind::Vec3:
      return glm::dvec3(v[0], v[1], v[2]);
    case ParamKind::Numbers:
      return v;
    default:
      break;
  }
  for (double x : v)
    if (!isWhole(x)) throw Error(cat(source, ": '", text, "' must be ", shapeOf(spec.kind)));
  if (spec.kind == ParamKind::Integer) return int(v[0]);
  return glm::ivec2(int(v[0]), int(v[1]));
}

std::vector<std::string> names(const std::vector<const char*>& list) {
  return {list.begin(), list.end()};
}

}  // namespace

bool ParamRange::contains(double x) const {
  if (min && (minOpen ? !(x > *min) : !(x >= *min))) return false;
  if (max && (maxOpen ? !(x < *max) : !(x <= *max))) return false;
  return true;
}

std::string ParamRange::text() const {
  if (min && max)
    return cat(minOpen ? "(" : "[", number(*min), ", ", number(*max), maxOpen ? ")" : "]");
  if (min) return cat(minOpen ? "> " : ">= ", number(*min));
  if (max) return cat(maxOpen ? "< " : "<= ", number(*max));
  return "";
}

std::string ParamSpec::flag() const {
  if (flagOverride) return flagOverride;
  std::string f = std::string("--") + name;
  std::replace(f.begin(), f.end(), '_', '-');
  return f;
}

std::string ParamSpec::defaultText(const CameraParams& defaults) const {
  if (defaultRule) {
    std::string text = defaultRule;
    const size_t slot = text.find("{}");
    if (defaultValue && slot != std::string::npos)
      text.replace(slot, 2, formatParamValue(*defaultValue));
    return text;
  }
  const std::optional<ParamValue> v = access.get(defaults);
  return v ? formatParamValue(*v) : "none";
}

void checkParamValue(const ParamSpec& spec, const ParamValue& value, const std::string& label) {
  const std::vector<double> parts = components(value);
  for (double x : parts) {
    if (!std::isfinite(x)) throw Error(cat(label, ": ", formatParamValue(value), " is not finite"));
    if (!spec.range.contains(x))
      throw Error(cat(label, ": ", formatParamValue(value), ": ",
                      parts.size() > 1 ? "each component must be " : "must be ",
                      spec.range.min && spec.range.max ? "in " : "", spec.range.text(),
                      *spec.unit ? cat(" ", spec.unit) : std::string()));
  }
  if (spec.kind == ParamKind::Choice) {
    const std::string& word = std::get<std::string>(value);
    const std::vector<const char*> choices = spec.choiceList();
    if (choices.empty()) return;  // `type`: checked by the registry
    if (std::find(choices.begin(), choices.end(), word) == choices.end()) {
      const std::string list = join(choices, ", ");
      throw Error(
          cat(label, ": '", word, "' is not one of ", list, didYouMean(word, names(choices))));
    }
  }
  if (spec.kind == ParamKind::Size && spec.maxPixels > 0) {
    const glm::ivec2 s = std::get<glm::ivec2>(value);
    if (double(s.x) * double(s.y) > spec.maxPixels)
      throw Error(
          cat(label, ": ", formatParamValue(value), " has more than ", spec.maxPixels, " pixels"));
  }
}

std::string formatParamValue(const ParamValue& v) {
  if (auto* x = std::get_if<std::string>(&v)) return *x;
  if (auto* x = std::get_if<bool>(&v)) return *x ? "true" : "false";
  if (auto* x = std::get_if<glm::ivec2>(&v)) return cat(x->x, "x", x->y);
  return join(components(v), ",", number);
}

ParamValue parseParamText(const ParamSpec& spec, const std::string& text,
                          const std::string& source) {
  switch (spec.kind) {
    case ParamKind::Flag:
      return true;
    case ParamKind::Choice:
      return text;
    default:
      return valueFromNumbers(spec, parseNumberList(spec, text, source), text, source);
  }
}

void ParamSet::set(const ParamSpec& spec, ParamValue value, std::string source) {
  erase(spec.name);
  entries_.push_back({&spec, std::move(value), std::move(source)});
}

const ParamSet::Entry* ParamSet::find(const std::string& name) const {
  for (const Entry& e : entries_)
    if (name == e.spec->name) return &e;
  return nullptr;
}

void ParamSet::erase(const std::string& name) {
  entries_.erase(std::remove_if(entries_.begin(), entries_.end(),
                                [&](const Entry& e) { return name == e.spec->name; }),
                 entries_.end());
}

std::string ParamSet::label(const ParamSpec& spec) const {
  const Entry* e = find(spec.name);
  return e ? e->source : spec.flag();
}

}  // namespace aperture
