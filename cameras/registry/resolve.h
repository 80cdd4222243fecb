#pragma once
// The parameters of the registered camera models (cameras/registry/registry.h): every declared
// spec, each once; a user's ParamSet checked and resolved for the model it names; the help line and
// the docs table. The schema (cameras/schema/param_schema.h) says what one parameter is; this side
// knows which models read it.
#include <string>
#include <vector>

#include "cameras/schema/param_schema.h"
#include "cameras/schema/params.h"

namespace aperture {

/// Every parameter of every registered camera model, each once, in a stable order (common
/// parameters first). What the command line registers as flags and job files accept as keys.
const std::vector<const ParamSpec*>& allCameraParamSpecs();
/// The spec of `name`, or null.
const ParamSpec* findCameraParamSpec(const std::string& name);

/// The parameters of `p` that differ from a default-constructed CameraParams, among those its
/// model reads (type included), each with `source`: resolving them gives `p` back.
ParamSet paramSetOf(const CameraParams& p, const std::string& source);

/// Checks and resolves a user's parameters, before any work: the camera type must be known
/// (with "did you mean"), every parameter must apply to that type, no two conflicting ones
/// may be given, every required companion must be given, and every value must lie in its
/// range. Errors name the sources (both of a conflicting pair). `base` supplies the values
/// of parameters not given (e.g. a job's size).
CameraParams resolveCameraParams(const ParamSet& given, CameraParams base = {});

/// The range checks of resolveCameraParams on already-resolved parameters (for callers that
/// fill CameraParams directly); errors name the parameter as `labels` does, or by its flag.
void checkCameraParamRanges(const CameraParams& p, const ParamSet* labels = nullptr);

/// A parameter's help with unit, default, range, choices (the registered models for `type`),
/// conflicts and companions by their flags: for --help.
std::string describeCameraParam(const ParamSpec& spec, const CameraParams& defaults = {});

/// Markdown table of every camera's parameters (docs/cameras.md embeds it verbatim).
std::string cameraParamsMarkdown();

}  // namespace aperture
