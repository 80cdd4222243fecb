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
  bool contains(double x) const;
  std::string text() const;  ///< "(0, 180)", "[1, 65536]", "> 0", ""
};

/// How a parameter sits in CameraParams: read its value (nothing when not set and no plain
/// default applies) and write a given value.
struct ParamAccess {
  std::optional<ParamValue> (*get)(const CameraParams&);
  void (*set)(CameraParams&, const ParamValue&);
};

struct ParamSpec {
  const char* name;  ///< snake_case: the job-file key and Python keyword
  ParamKind kind;
  const char* unit;  ///< "degrees", "scene units", "pixels", "mm", "" for none
  const char* help;
  /// What applies when the parameter is not given and CameraParams has no plain default for
  /// it ("45 vertical, unless viewport or focal_length is given"); null: the default is the
  /// value of a default-constructed CameraParams, printed from `access.get`.
  const char* defaultRule;
  ParamRange range;
  std::vector<const char*> choices;    ///< for Choice; empty: the registered camera models
  std::vector<const char*> conflicts;  ///< parameters that may not be given with this one
  std::vector<const char*> needs;      ///< parameters that must be given with this one
  ParamAccess access;
  /// The command-line flag when it is not "--" + name with '_' as '-' (only `type`: --camera).
  const char* flagOverride = nullptr;
  /// For Numbers: how many (0: any number, at least one).
  size_t count = 0;
  /// A model this parameter selects when given without `type` (the pose matrices and
  /// intrinsics select "calibrated"); null: the default type applies.
  const char* selectsModel = nullptr;
  /// For Choice: the choices as a table holds them when asked (a table that can grow: the lens
  /// models, cameras/lens_model.h); null: `choices`.
  std::vector<const char*> (*choicesNow)() = nullptr;

  /// The choices of a Choice parameter (choicesNow() or choices; empty: the camera models).
  std::vector<const char*> choiceList() const { return choicesNow ? choicesNow() : choices; }
  std::string flag() const;  ///< "--fov", "--focal-length", "--camera"
  /// The rule, or the value `defaults` holds (a command's own defaults, e.g. its size).
  std::string defaultText(const CameraParams& defaults = {}) const;
  /// Help with unit, default, range, choices, conflicts and companions: for --help.
  std::string describeText(const CameraParams& defaults = {}) const;
};

/// Text form of a value ("1.5", "0,1,0", "640x480", "true").
std::string formatParamValue(const ParamValue& v);

/// Parses the command-line text of a value; Error names `source` (e.g. "--fov") and the text.
ParamValue parseParamText(const ParamSpec& spec, const std::string& text,
                          const std::string& source);

/// Parameters given by a user, each with where it came from ("--fov", "cameras[2].fov"), in
/// the order given. Resolve with resolveCameraParams().
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
  std::string label(const std::string& name) const;

 private:
  std::vector<Entry> entries_;
};

/// The parameters of `p` that differ from a default-constructed CameraParams, among those its
/// model reads (type included), each with `source`: resolving them gives `p` back.
ParamSet paramSetOf(const CameraParams& p, const std::string& source);

/// Every parameter of every registered camera model, each once, in a stable order (common
/// parameters first). What the command line registers as flags and job files accept as keys.
const std::vector<const ParamSpec*>& allCameraParamSpecs();
/// The spec of `name`, or null.
const ParamSpec* findCameraParamSpec(const std::string& name);

/// Checks and resolves a user's parameters, before any work: the camera type must be known
/// (with "did you mean"), every parameter must apply to that type, no two conflicting ones
/// may be given, every required companion must be given, and every value must lie in its
/// range. Errors name the sources (both of a conflicting pair). `base` supplies the values
/// of parameters not given (e.g. a job's size).
CameraParams resolveCameraParams(const ParamSet& given, CameraParams base = {});

/// The range checks of resolveCameraParams on already-resolved parameters (for callers that
/// fill CameraParams directly); errors name the parameter as `labels` does, or by its flag.
void checkCameraParamRanges(const CameraParams& p, const ParamSet* labels = nullptr);

/// Markdown table of every camera's parameters (docs/cameras.md embeds it verbatim).
std::string cameraParamsMarkdown();

/// Field accessors for the common member types (optional fields read as "not set").
template <auto Member>
ParamAccess fieldAccess();

}  // namespace aperture

#include "cameras/schema/param_access.h"
