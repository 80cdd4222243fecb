// Tests generated from the camera parameter schema (cameras/schema/param_schema.h): for every
// declared parameter, its default is what a camera without it uses, its range ends are
// accepted or refused as declared (through the command-line and the job-file front ends),
// and every declared conflict and companion is enforced with a message naming both sides.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/jobs/job.h"
#include "cameras/models/base.h"
#include "cameras/registry/describe.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/param_schema.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// The first model that reads `spec`.
const CameraModel& modelOf(const ParamSpec& spec) {
  for (const CameraModel* m : cameraModels())
    if (m->accepts(spec.name)) return *m;
  throw Error(cat("no model reads ", spec.name));
}

bool isNumeric(const ParamSpec& s) {
  return s.kind != ParamKind::Flag && s.kind != ParamKind::Choice;
}

/// A value of the spec's kind with every component x.
ParamValue valueOf(const ParamSpec& s, double x) {
  switch (s.kind) {
    case ParamKind::Number:
      return x;
    case ParamKind::Integer:
      return int(x);
    case ParamKind::Vec2:
      return glm::dvec2(x);
    case ParamKind::Vec3:
      return glm::dvec3(x);
    case ParamKind::Size:
      return glm::ivec2(int(x), 1);  // the pixel-count limit stays clear
    case ParamKind::Numbers:
      return std::vector<double>(s.count ? s.count : 1, x);
    default:
      break;
  }
  throw Error("not numeric");
}

/// A value for `spec` that passes its range (for conflict and companion checks).
ParamValue validValue(const ParamSpec& s) {
  if (s.kind == ParamKind::Flag) return true;
  if (s.kind == ParamKind::Choice)
    return std::string(s.choices.empty() ? "perspective" : s.choices.front());
  double x = 0.5;
  if (s.range.min && !s.range.contains(x)) x = *s.range.min + 1.0;
  return valueOf(s, x);
}

/// Resolves `spec` = value for the spec's first model; the error message, or "".
std::string resolveError(const ParamSpec& spec, const ParamValue& v) {
  ParamSet given;
  given.set(*findCameraParamSpec("type"), std::string(modelOf(spec).name), "--camera");
  given.set(spec, v, spec.flag());
  for (const char* needed : spec.needs) {
    const ParamSpec& n = *findCameraParamSpec(needed);
    given.set(n, validValue(n), n.flag());
  }
  try {
    resolveCameraParams(given);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// The step just past a bound: the smallest relative step integers and doubles both see.
double outside(double bound, bool above, ParamKind kind) {
  const double step = kind == ParamKind::Integer || kind == ParamKind::Size
                          ? 1.0
                          : std::max(1e-9, std::abs(bound) * 1e-9);
  return above ? bound + step : bound - step;
}

TEST(ParamSchema, EveryParameterIsDeclaredOnceAndReadByAModel) {
  const auto& all = allCameraParamSpecs();
  ASSERT_GE(all.size(), 20u);
  for (const ParamSpec* s : all) {
    SCOPED_TRACE(s->name);
    EXPECT_EQ(findCameraParamSpec(s->name), s);
    EXPECT_NO_THROW(modelOf(*s));
    EXPECT_FALSE(std::string(s->help).empty());
    for (const char* c : s->conflicts) EXPECT_NE(findCameraParamSpec(c), nullptr) << c;
    for (const char* c : s->needs) EXPECT_NE(findCameraParamSpec(c), nullptr) << c;
  }
}

// Range ends, for every numeric parameter: a closed end is accepted, an open end refused,
// and a value just outside either end refused with a message naming the flag and the value.
TEST(ParamSchema, RangeEndsAreAcceptedOrRefusedAsDeclared) {
  int checked = 0;
  for (const ParamSpec* s : allCameraParamSpecs()) {
    if (!isNumeric(*s)) continue;
    SCOPED_TRACE(s->name);
    auto expectEnd = [&](std::optional<double> bound, bool open, bool upper) {
      if (!bound) return;
      const std::string atEnd = resolveError(*s, valueOf(*s, *bound));
      if (open)
        EXPECT_NE(atEnd.find(s->flag()), std::string::npos) << "open end accepted: " << *bound;
      else
        EXPECT_EQ(atEnd, "") << "closed end refused: " << *bound;
      const ParamValue past = valueOf(*s, outside(*bound, upper, s->kind));
      const std::string msg = resolveError(*s, past);
      EXPECT_NE(msg.find(s->flag() + ": " + formatParamValue(past)), std::string::npos) << msg;
      ++checked;
    };
    expectEnd(s->range.min, s->range.minOpen, false);
    expectEnd(s->range.max, s->range.maxOpen, true);
    // Non-finite values are refused whatever the range (whole-number kinds cannot hold them).
    if (s->kind != ParamKind::Integer && s->kind != ParamKind::Size) {
      EXPECT_NE(resolveError(*s, valueOf(*s, NAN)).find("not finite"), std::string::npos);
    }
  }
  EXPECT_GE(checked, 15);
}

// The same range ends through job files: the message names the file and the JSON key.
TEST(ParamSchema, RangeEndsAreRefusedInJobFilesWithTheKey) {
  for (const ParamSpec* s : allCameraParamSpecs()) {
    if (!isNumeric(*s) || !s->range.min) continue;
    SCOPED_TRACE(s->name);
    const double bad = outside(*s->range.min, false, s->kind);
    nlohmann::json cam = {{"name", "c"}, {"type", modelOf(*s).name}, {"eye", {0, 0, 5}}};
    if (std::string(s->name) != "dir") cam["at"] = {0, 0, 0};
    const ParamValue v = valueOf(*s, bad);
    nlohmann::json value;
    if (auto* x = std::get_if<double>(&v)) value = *x;
    if (auto* x = std::get_if<int>(&v)) value = *x;
    if (auto* x = std::get_if<glm::dvec2>(&v)) value = {x->x, x->y};
    if (auto* x = std::get_if<glm::dvec3>(&v)) value = {x->x, x->y, x->z};
    if (auto* x = std::get_if<glm::ivec2>(&v)) value = {x->x, x->y};
    cam[s->name] = value;
    const nlohmann::json job = {{"scene", {{"meshes", {{{"path", "procedural:cube"}}}}}},
                                {"cameras", {cam}},
                                {"output", "out/{camera}.exr"}};
    try {
      app::parseJobText(job.dump(), "job.json", "");
      ADD_FAILURE() << "accepted " << s->name << " = " << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("job.json: cameras[0]." + std::string(s->name)),
                std::string::npos)
          << e.what();
    }
  }
}

// Every declared conflict is refused with both flags in the message; every declared companion
// is required, naming both.
TEST(ParamSchema, ConflictsAndCompanionsAreEnforcedNamingBothFlags) {
  int pairs = 0;
  for (const ParamSpec* s : allCameraParamSpecs()) {
    const CameraModel& model = modelOf(*s);
    for (const char* other : s->conflicts) {
      const ParamSpec& o = *findCameraParamSpec(other);
      if (!model.accepts(other)) continue;
      ParamSet given;
      given.set(*findCameraParamSpec("type"), std::string(model.name), "--camera");
      given.set(*s, validValue(*s), s->flag());
      given.set(o, validValue(o), o.flag());
      try {
        resolveCameraParams(given);
        ADD_FAILURE() << s->name << " with " << other << " accepted";
      } catch (const Error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find(s->flag()), std::string::npos) << m;
        EXPECT_NE(m.find(o.flag()), std::string::npos) << m;
        EXPECT_NE(m.find("conflict"), std::string::npos) << m;
      }
      ++pairs;
    }
    for (const char* needed : s->needs) {
      ParamSet given;
      given.set(*findCameraParamSpec("type"), std::string(model.name), "--camera");
      given.set(*s, validValue(*s), s->flag());
      try {
        resolveCameraParams(given);
        ADD_FAILURE() << s->name << " without " << needed << " accepted";
      } catch (const Error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find(s->flag()), std::string::npos) << m;
        EXPECT_NE(m.find(findCameraParamSpec(needed)->flag()), std::string::npos) << m;
      }
      ++pairs;
    }
  }
  EXPECT_GE(pairs, 8);
}

// A parameter a model does not read is refused for that model, naming the models that do.
TEST(ParamSchema, ParametersOfOtherModelsAreRefused) {
  for (const ParamSpec* s : allCameraParamSpecs())
    for (const CameraModel* m : cameraModels()) {
      if (m->accepts(s->name)) continue;
      ParamSet given;
      given.set(*findCameraParamSpec("type"), std::string(m->name), "--camera");
      given.set(*s, validValue(*s), s->flag());
      try {
        resolveCameraParams(given);
        ADD_FAILURE() << s->name << " accepted by " << m->name;
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(s->flag() + ": does not apply to a '" + m->name),
                  std::string::npos)
            << e.what();
      }
    }
}

/// The rays of a camera as a hash (the same camera gives the same hash).
std::string rayHash(const CameraParams& p) {
  const auto cam = makeCameraModel(p);
  test::Fnv1a h;
  for (int i = 0; i < p.height; i += 7)
    for (int j = 0; j < p.width; j += 5) {
      glm::dvec3 org, dir;
      const bool ok = cam->ray(j + 0.5, i + 0.5, 0.3, 0.7, org, dir);
      h.add(&ok, sizeof ok);
      h.add(&org, sizeof org);
      h.add(&dir, sizeof dir);
    }
  const CameraDescription d = cam->describe();
  h.add(&d.d, sizeof d.d);
  h.add(&d.vw, sizeof d.vw);
  h.add(&d.vh, sizeof d.vh);
  return h.hex();
}

/// The minimal flags each model needs beside the parameter under test.
std::string baseFlags(const CameraModel& m) {
  std::string f = std::string("--camera ") + m.name + " --eye 0.3,0.4,5 --at 0,0,0 --size 64,48";
  if (m.accepts("viewport") && !m.accepts("fov")) f += " --viewport 2,1.5";
  if (m.accepts("oblique_dir")) f += " --oblique-angles 10,5";
  if (m.accepts("intrinsics")) f += " --intrinsics 60,60,32,24";
  return f;
}

// Defaults: a camera given a parameter at its declared default equals the camera without it,
// for every model that reads it. Defaults stated as rules are checked at their closed form.
TEST(ParamSchema, DefaultsAreWhatACameraWithoutTheParameterUses) {
  struct Rule {
    const char* name;
    const char* flags;  ///< the rule's value, given explicitly
    const char* extra;  ///< what the rule depends on, given to both
  };
  const double focus = glm::length(glm::dvec3(0.3, 0.4, 5.0));  // |at − eye| with at = 0
  char focusFlag[64];
  std::snprintf(focusFlag, sizeof focusFlag, "--focus %.17g", focus);
  const std::vector<Rule> rules = {{"fov", "--fov 45 --fov-axis y", ""},
                                   {"d", "--d 1", "--viewport 0.8,0.6"},
                                   {"focus", focusFlag, ""}};
  int checked = 0;
  for (const ParamSpec* s : allCameraParamSpecs())
    for (const CameraModel* m : cameraModels()) {
      if (!m->accepts(s->name)) continue;
      SCOPED_TRACE(std::string(s->name) + " on " + m->name);
      std::string with, extra;
      if (!s->defaultRule) {
        const auto v = s->access.get(CameraParams{});
        if (!v || s->kind == ParamKind::Flag) continue;
        with = s->flag() + " " + formatParamValue(*v);
      } else {
        bool found = false;
        for (const Rule& r : rules)
          if (r.name == std::string(s->name)) with = r.flags, extra = r.extra, found = true;
        if (!found) continue;  // eye, at, oblique_*: defaults the command line decides
      }
      if (std::string(s->name) == "type" || std::string(s->name) == "size") continue;
      for (const char* needed : s->defaultRule ? std::vector<const char*>() : s->needs) {
        const ParamSpec& n = *findCameraParamSpec(needed);
        extra += " " + n.flag() + " " + formatParamValue(validValue(n));
      }
      const std::string base = baseFlags(*m) + " " + extra;
      EXPECT_EQ(rayHash(test::cameraParamsFromFlags(base)),
                rayHash(test::cameraParamsFromFlags(base + " " + with)))
          << with;
      ++checked;
    }
  EXPECT_GE(checked, 15);
}

// The wrong default would be caught: 46° instead of 45°, or a focus 1% off, changes the rays.
TEST(ParamSchema, TheDefaultsCheckCatchesAWrongDefault) {
  const std::string base = "--eye 0.3,0.4,5 --at 0,0,0 --size 64,48";
  EXPECT_NE(rayHash(test::cameraParamsFromFlags(base)),
            rayHash(test::cameraParamsFromFlags(base + " --fov 46")));
  const std::string lens = "--camera thinlens --aperture 0.1 " + base;
  EXPECT_NE(rayHash(test::cameraParamsFromFlags(lens)),
            rayHash(test::cameraParamsFromFlags(lens + " --focus 5.075")));
}

TEST(ParamSchema, SizeAcceptsCommaAndTimesForms) {
  const CameraParams a = test::cameraParamsFromFlags("--eye 0,0,5 --at 0,0,0 --size 640x480");
  const CameraParams b = test::cameraParamsFromFlags("--eye 0,0,5 --at 0,0,0 --size 640,480");
  EXPECT_EQ(a.width, 640);
  EXPECT_EQ(a.height, 480);
  EXPECT_EQ(b.width, 640);
  EXPECT_EQ(b.height, 480);
  EXPECT_THROW(test::cameraParamsFromFlags("--eye 0,0,5 --at 0,0,0 --size 640x480x2"), Error);
  EXPECT_THROW(test::cameraParamsFromFlags("--eye 0,0,5 --at 0,0,0 --size 640.5,480"), Error);
}

TEST(ParamSchema, DocsTableIsTheGeneratedOne) {
  const std::string docs = test::readFile(std::string(APERTURE_TESTS_DIR) + "/../docs/cameras.md");
  EXPECT_NE(docs.find(cameraParamsMarkdown()), std::string::npos)
      << "docs/cameras.md does not hold the generated table; regenerate it with "
         "`aperture camera --params-table` and paste it between the markers";
}

}  // namespace

namespace {

// --describe lists every parameter the model reads, with the given value or the default.
TEST(ParamSchema, DescribeListsEveryParameterOfTheModel) {
  for (const CameraModel* m : cameraModels()) {
    SCOPED_TRACE(m->name);
    const CameraParams p = test::cameraParamsFromFlags(baseFlags(*m) + " --spp 3");
    const std::string text = describeParameters(p);
    for (const ParamSpec* s : m->params)
      EXPECT_NE(text.find("\n  " + std::string(s->name) + " = "), std::string::npos) << s->name;
    EXPECT_NE(text.find("\n  spp = 3\n"), std::string::npos) << text;
    for (const ParamSpec* s : allCameraParamSpecs()) {
      if (m->accepts(s->name)) continue;
      EXPECT_EQ(text.find("\n  " + std::string(s->name) + " = "), std::string::npos) << s->name;
    }
  }
}

}  // namespace
