#pragma once
// Reading job files (JSON) with messages that name the file and the JSON path of a value
// ("cameras[2].eye"): typed getters, known keys with "did you mean", and no silent leftovers.
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/util/error.h"

namespace aperture::app {

using nlohmann::json;

/// A JSON object with a fixed set of known keys, read through typed getters whose errors
/// name the file and the JSON path ("cameras[2].eye").
class Object {
 public:
  /// Checks that `j` is an object whose keys are all in `known` (an unknown key is an
  /// error listing the known ones, with "did you mean").
  Object(const std::string& file, std::string path, const json& j,
         const std::vector<std::string>& known);

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw Error(cat(file_, ": ", where.empty() ? "(top level)" : where, ": ", what));
  }
  std::string keyPath(const std::string& key) const {
    for (const auto& [placedKey, where] : placed_)
      if (placedKey == key) return where;
    return path_.empty() ? key : path_ + "." + key;
  }
  /// For an object merged from several places (an entry of "scenes" over the job's shared
  /// keys): messages name `key` at `where`, the path it was written at, instead of path.key.
  void placeKey(const std::string& key, std::string where) {
    placed_.emplace_back(key, std::move(where));
  }
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  bool has(const char* key) const { return j_.contains(key); }
  const json* find(const char* key) const {
    auto it = j_.find(key);
    return it == j_.end() ? nullptr : &*it;
  }
  const json& required(const char* key) const {
    const json* v = find(key);
    if (!v) fail(keyPath(key), "required key is missing");
    return *v;
  }

  static std::string typeName(const json& v) {
    if (v.is_number_integer()) return "an integer";
    if (v.is_number()) return "a number";
    if (v.is_string()) return "a string";
    if (v.is_boolean()) return "a boolean";
    if (v.is_array()) return "an array";
    if (v.is_object()) return "an object";
    return "null";
  }

  double toNumber(const std::string& where, const json& v) const {
    if (!v.is_number()) fail(where, cat("expected a number, got ", typeName(v)));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(where, "expected a finite number");
    return x;
  }
  int toInt(const std::string& where, const json& v) const {
    if (v.is_number_unsigned()) {
      if (v.get<uint64_t>() > uint64_t(INT_MAX)) fail(where, "integer out of range");
      return int(v.get<uint64_t>());
    }
    if (!v.is_number_integer()) fail(where, cat("expected an integer, got ", typeName(v)));
    const int64_t x = v.get<int64_t>();
    if (x < INT_MIN || x > INT_MAX) fail(where, "integer out of range");
    return int(x);
  }
  std::vector<double> toNumbers(const std::string& where, const json& v, size_t n) const {
    if (!v.is_array() || v.size() != n)
      fail(where, cat("expected an array of ", n, " numbers, got ", typeName(v)));
    std::vector<double> out;
    for (size_t k = 0; k < n; ++k) out.push_back(toNumber(cat(where, "[", k, "]"), v[k]));
    return out;
  }

  std::optional<double> number(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    return toNumber(keyPath(key), *v);
  }
  double number(const char* key, double def) const { return number(key).value_or(def); }
  std::optional<int> integer(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    return toInt(keyPath(key), *v);
  }
  int integer(const char* key, int def) const { return integer(key).value_or(def); }
  bool boolean(const char* key, bool def) const {
    const json* v = find(key);
    if (!v) return def;
    if (!v->is_boolean()) fail(keyPath(key), cat("expected true or false, got ", typeName(*v)));
    return v->get<bool>();
  }
  std::optional<std::string> string(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    if (!v->is_string()) fail(keyPath(key), cat("expected a string, got ", typeName(*v)));
    return v->get<std::string>();
  }
  std::optional<glm::dvec3> vec3(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    auto x = toNumbers(keyPath(key), *v, 3);
    return glm::dvec3(x[0], x[1], x[2]);
  }
  std::optional<glm::dvec2> vec2(const char* key) const {
    const json* v = find(key);
    if (!v) return std::nullopt;
    auto x = toNumbers(keyPath(key), *v, 2);
    return glm::dvec2(x[0], x[1]);
  }
  const json& array(const char* key) const {
    const json& v = required(key);
    if (!v.is_array()) fail(keyPath(key), cat("expected an array, got ", typeName(v)));
    return v;
  }

  /// The object itself.
  const json& raw() const { return j_; }

 private:
  const std::string& file_;
  std::string path_;
  const json& j_;
  std::vector<std::pair<std::string, std::string>> placed_;
};

/// "path[k]".
std::string indexPath(const std::string& path, size_t k);

}  // namespace aperture::app
