// Tests of cameras/registry/resolve.cpp and of the one place a parameter's default and range live
// (its ParamSpec): the code that applies a default reads the spec's value, and the help line and
// the range checks come from the same declaration.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "apps/services/command_camera.h"
#include "cameras/models/base.h"
#include "cameras/models/thinlens.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/conventions.h"
#include "core/util/error.h"
#include "core/util/units.h"

using namespace aperture;

namespace {

// A default stated with a value shows that value in its text ("{}" in the rule), and the
// value lies in the spec's own range.
TEST(Resolve, DefaultTextsStateTheValueTheCodeApplies) {
  int withValue = 0;
  for (const ParamSpec* s : allCameraParamSpecs()) {
    if (!s->defaultValue) continue;
    SCOPED_TRACE(s->name);
    ++withValue;
    ASSERT_NE(s->defaultRule, nullptr);
    EXPECT_NE(std::string(s->defaultRule).find("{}"), std::string::npos);
    EXPECT_NE(s->defaultText().find(formatParamValue(*s->defaultValue)), std::string::npos)
        << s->defaultText();
    EXPECT_NO_THROW(checkParamValue(*s, *s->defaultValue, s->flag()));
  }
  EXPECT_GE(withValue, 3);  // fov, d, focus
}

// A camera given neither fov, viewport nor focal length spans the fov spec's default
// vertically at the d spec's default: vh = 2·d·tan(fov / 2), vw = vh·W/H.
TEST(Resolve, ACameraWithoutFovUsesTheSpecsDefaults) {
  CameraParams p;
  p.width = 200;
  p.height = 100;
  const auto cam = makeCameraModel(p);
  const double fov = fovParamSpec().defaultAs<double>();
  const double d = distanceParamSpec().defaultAs<double>();
  EXPECT_EQ(cam->d(), d);
  EXPECT_NEAR(cam->vh(), 2.0 * d * std::tan(0.5 * fov * kRadPerDeg), 1e-12);
  EXPECT_NEAR(cam->vw(), 2.0 * cam->vh(), 1e-12);
  // A thin lens without a look-at point or focus is focused at the focus spec's default.
  p.type = "thinlens";
  p.apertureRadius = 0.1;
  EXPECT_EQ(focusDistanceOf(p), findCameraParamSpec("focus")->defaultAs<double>());
}

// The command line frames the scene for the fov the camera will use: with no fov given, the
// spec's default, the bounding sphere (radius r) fits at 0.8·r / sin(fov / 2).
TEST(Resolve, FramingUsesTheFovTheCameraUses) {
  const glm::dvec3 lo(-1.0), hi(1.0);
  const double r = std::sqrt(3.0);
  auto distance = [&](const ParamSet& given) {
    const CameraParams p = app::resolveCommandCamera(given, CameraParams{}, lo, hi);
    return glm::length(p.eye - *p.at);
  };
  const double fov = fovParamSpec().defaultAs<double>();
  EXPECT_NEAR(distance(ParamSet()), 0.8 * r / std::sin(0.5 * fov * kRadPerDeg), 1e-12);
  ParamSet narrow;
  narrow.set(fovParamSpec(), 20.0, "--fov");
  EXPECT_NEAR(distance(narrow), 0.8 * r / std::sin(10.0 * kRadPerDeg), 1e-12);
}

// fov's range is the planar full-angle range the pbrt-v4 and Mitsuba 3 converters check:
// both refuse its open end.
TEST(Resolve, FovRangeIsThePlanarAngleRange) {
  EXPECT_EQ(fovParamSpec().range.text(), kPlanarFovRangeDeg.text());
  EXPECT_EQ(fovParamSpec().range.text(), "(0, 180)");
  const double end = *kPlanarFovRangeDeg.max;
  EXPECT_THROW(fromPbrt(end, 10, 10), Error);
  EXPECT_THROW(fromMitsuba(end, MitsubaFovAxis::X, 10, 10), Error);
  EXPECT_NO_THROW(fromPbrt(std::nextafter(end, 0.0), 10, 10));
}

// The --help line: the registered models for `type`, conflicts and companions by their flags.
TEST(Resolve, HelpLinesNameModelsAndFlags) {
  const std::string type = describeCameraParam(*findCameraParamSpec("type"));
  std::string models;
  for (const std::string& name : cameraTypeNames()) models += (models.empty() ? "" : "|") + name;
  EXPECT_NE(type.find(models), std::string::npos) << type;
  const std::string fov = describeCameraParam(fovParamSpec());
  EXPECT_NE(fov.find("not with --focal-length, --viewport"), std::string::npos) << fov;
  EXPECT_NE(fov.find("range (0, 180)"), std::string::npos) << fov;
  const std::string d = describeCameraParam(distanceParamSpec());
  EXPECT_NE(d.find("needs --viewport"), std::string::npos) << d;
}

// A companion that is not given is named by its flag, a conflicting pair by both sources.
TEST(Resolve, MessagesNameFlagsAndSources) {
  ParamSet given;
  given.set(distanceParamSpec(), 2.0, "cameras[0].d");
  try {
    resolveCameraParams(given);
    ADD_FAILURE() << "d without viewport accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "cameras[0].d needs --viewport as well");
  }
  EXPECT_EQ(given.label(distanceParamSpec()), "cameras[0].d");
  EXPECT_EQ(given.label(viewportParamSpec()), "--viewport");
}

}  // namespace
