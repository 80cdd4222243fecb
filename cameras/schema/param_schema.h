#pragma once
// The camera parameter schema: every camera parameter is declared once, by the camera module
// that reads it (name, kind, unit, default, range, conflicts, help, and how it sits in
// CameraParams). The command line (apps/cli/camera_flags.cpp), job files
// (apps/jobs/job_camera.cpp), Python, `aperture camera --describe`, validation messages and the
// table in docs/cameras.md are all generated from these declarations. See docs/architecture.md for
// the path of one parameter from a flag to a packet.
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "cameras/schema/params.h"

namespace aperture {

/// The kinds of value a parameter takes, with their text forms (command line).
enum class ParamKind {
  Number,   ///< "1.5"
  Integer,  ///< "4"
  Vec2,     ///< "A,B"
  Vec3,     ///< "X,Y,Z"
  Size,     ///< "W,H" or "WxH", whole numbers
  Flag,     ///< present or not (true / false in job files)
  Choice,   ///< one word of a fixed list
  Numbers,  ///< "A,B,C,..." (ParamSpec::count of them, or any number when 0)
};

using ParamValue = std::variant<double, int, glm::dvec2, glm::dvec3, glm::ivec2, bool, std::string,
                                std::vector<double>>;

/// Bounds of a numeric value, applied to every component; values must also be finite.
struct ParamRange {
  std::optional<double> min, max;
  bool minOpen = false, maxOpen = false;  ///< exclusive bounds
  /// (lo, hi), [lo, hi], (lo, hi], > lo, >= lo.
  static constexpr ParamRange open(double lo, double hi) { return {lo, hi, true, true}; }
  static constexpr ParamRange closed(double lo, double hi) { return {lo, hi, false, false}; }
  static constexpr ParamRange openClosed(double lo, double hi) { return {lo, hi, true, false}; }
  static constexpr ParamRange above(double lo) { return {lo, std::nullopt, true, false}; }
  static constexpr ParamRange atLeast(double lo) { return {lo, std::nullopt, false, false}; }
  bool contains(double x) const;
  std::string text() const;  ///< "(0, 180)", "[1, 65536]", "> 0", ""
};

/// How a parameter sits in CameraParams: read its value (nothing when not set and no plain
/// default applies) and write a given value.
struct ParamAccess {
  std::optional<ParamValue> (*get)(const CameraParams&);
  void (*set)(CameraParams&, const ParamValue&);
};

/// One camera parameter, declared once by the module that reads it. C++17 has no designated
/// initialisers, so a declaration names each field it sets through a setter of the same
/// meaning (`withUnit` sets `unit`, ...); what it does not name keeps the default below:
///
///     const ParamSpec kFov =
///         ParamSpec("fov", ParamKind::Number, fieldAccess<&CameraParams::fovDeg>())
///             .withUnit("degrees")
///             .withHelp("Field of view")
///             .withDefault(45.0, "{} vertical, when neither viewport nor focal_length is given")
///             .withRange(ParamRange::open(0.0, 180.0))
///             .withConflicts({"focal_length", "viewport"});
///
/// The setters take and give the declaration being built (an rvalue), so a spec is written
/// in one expression and is const afterwards.
struct ParamSpec {
  const char* name;  ///< snake_case: the job-file key and Python keyword
  ParamKind kind;
  ParamAccess access;     ///< how it sits in CameraParams
  const char* unit = "";  ///< "degrees", "scene units", "pixels", "mm", "" for none
  const char* help = "";
  /// What applies when the parameter is not given and CameraParams has no plain default for
  /// it ("{} vertical, unless viewport or focal_length is given", "{}" standing for
  /// `defaultValue`); null: the default is the value of a default-constructed CameraParams,
  /// printed from `access.get`.
  const char* defaultRule = nullptr;
  /// The value the rule applies (fov's 45, d's 1), for the code that applies it to read
  /// (defaultAs); none when the rule names no value.
  std::optional<ParamValue> defaultValue;
  ParamRange range;
  std::vector<const char*> choices;    ///< for Choice; empty: the registered camera models
  std::vector<const char*> conflicts;  ///< parameters that may not be given with this one
  std::vector<const char*> needs;      ///< parameters that must be given with this one
  /// The command-line flag when it is not "--" + name with '_' as '-' (only `type`: --camera).
  const char* flagOverride = nullptr;
  /// For Numbers: how many (0: any number, at least one).
  size_t count = 0;
  /// For Size: at most this many pixels (width x height); 0: no limit beyond the range.
  double maxPixels = 0;
  /// A model this parameter selects when given without `type` (the pose matrices and
  /// intrinsics select "calibrated"); null: the default type applies.
  const char* selectsModel = nullptr;
  /// For Choice: the choices as a table holds them when asked (a table that can grow: the lens
  /// models, cameras/lens_model.h); null: `choices`.
  std::vector<const char*> (*choicesNow)() = nullptr;

  /// The choices of a Choice parameter (choicesNow() or choices; empty: the camera models).
  std::vector<const char*> choiceList() const { return choicesNow ? choicesNow() : choices; }

  ParamSpec(const char* paramName, ParamKind paramKind, ParamAccess paramAccess)
      : name(paramName), kind(paramKind), access(paramAccess) {}
  ParamSpec&& withUnit(const char* u) && {
    unit = u;
    return std::move(*this);
  }
  ParamSpec&& withHelp(const char* h) && {
    help = h;
    return std::move(*this);
  }
  /// A default stated as a rule only (eye: "frames the scene").
  ParamSpec&& withDefaultRule(const char* rule) && {
    defaultRule = rule;
    return std::move(*this);
  }
  /// A default value with the rule it applies under; "{}" in the rule stands for the value.
  ParamSpec&& withDefault(ParamValue value, const char* rule) && {
    defaultValue = std::move(value);
    defaultRule = rule;
    return std::move(*this);
  }
  ParamSpec&& withRange(ParamRange r) && {
    range = r;
    return std::move(*this);
  }
  ParamSpec&& withChoices(std::vector<const char*> c) && {
    choices = std::move(c);
    return std::move(*this);
  }
  ParamSpec&& withConflicts(std::vector<const char*> c) && {
    conflicts = std::move(c);
    return std::move(*this);
  }
  ParamSpec&& withNeeds(std::vector<const char*> n) && {
    needs = std::move(n);
    return std::move(*this);
  }
  ParamSpec&& withFlag(const char* f) && {
    flagOverride = f;
    return std::move(*this);
  }
  ParamSpec&& withCount(size_t n) && {
    count = n;
    return std::move(*this);
  }
  ParamSpec&& withMaxPixels(double n) && {
    maxPixels = n;
    return std::move(*this);
  }
  ParamSpec&& withSelectsModel(const char* m) && {
    selectsModel = m;
    return std::move(*this);
  }
  ParamSpec&& withChoicesNow(std::vector<const char*> (*c)()) && {
    choicesNow = c;
    return std::move(*this);
  }

  std::string flag() const;  ///< "--fov", "--focal-length", "--camera"
  /// The rule (with the value in place of "{}"), or the value `defaults` holds (a command's
  /// own defaults, e.g. its size).
  std::string defaultText(const CameraParams& defaults = {}) const;
  /// defaultValue as a T (double for a Number); throws std::bad_optional_access or
  /// std::bad_variant_access when the spec declares no value of that type.
  template <class T>
  T defaultAs() const {
    return std::get<T>(defaultValue.value());
  }
};

/// Throws Error, naming `label` ("--fov", "cameras[2].fov"), the value, the range and the unit,
/// when `value` lies outside the spec's range, is not finite, is not one of its choices or
/// (Size) has more than maxPixels pixels. The `type` choice (no fixed list) is left to the
/// registry.
void checkParamValue(const ParamSpec& spec, const ParamValue& value, const std::string& label);

/// Text form of a value ("1.5", "0,1,0", "640x480", "true").
std::string formatParamValue(const ParamValue& v);

/// Parses the command-line text of a value; Error names `source` (e.g. "--fov") and the text.
ParamValue parseParamText(const ParamSpec& spec, const std::string& text,
                          const std::string& source);

/// Parameters given by a user, each with where it came from ("--fov", "cameras[2].fov"), in
/// the order given. Resolve with resolveCameraParams() (cameras/registry/resolve.h).
class ParamSet {
 public:
  struct Entry {
    const ParamSpec* spec;
    ParamValue value;
    std::string source;
  };
  /// Adds (or replaces) a value; the value must be of the spec's kind.
  void set(const ParamSpec& spec, ParamValue value, std::string source);
  const Entry* find(const std::string& name) const;
  bool has(const std::string& name) const { return find(name) != nullptr; }
  void erase(const std::string& name);
  const std::vector<Entry>& entries() const { return entries_; }
  /// How messages name a parameter: its source when given, else its flag.
  std::string label(const ParamSpec& spec) const;

 private:
  std::vector<Entry> entries_;
};

/// Field accessors for the common member types (optional fields read as "not set").
template <auto Member>
ParamAccess fieldAccess();

}  // namespace aperture

#include "cameras/schema/param_access.h"
