#pragma once
// The camera flags of render, bench, camera and tradeoff, generated from the camera parameter
// schema (cameras/schema/param_schema.h), and the command-line camera's resolution against a scene.
#include <CLI/CLI.hpp>
#include <deque>
#include <string>

#include "apps/services/scene_setup.h"
#include "cameras/schema/param_schema.h"

namespace aperture::app {

class CameraFlags {
 public:
  /// Registers a flag for every camera parameter of every model, with help generated from
  /// the schema; `defaults` are the command's own (e.g. bench renders 1920x1080).
  void add(CLI::App& app, const CameraParams& defaults = {});
  /// What the command line gave (call after parsing), each value with its flag as source.
  /// With --cameras, the parameters of the one image --image names come first (from the
  /// camera file) and the flags given override them.
  ParamSet given() const;
  CameraParams& defaults() { return defaults_; }
  const CameraParams& defaults() const { return defaults_; }

 private:
  struct Slot {
    const ParamSpec* spec;
    CLI::Option* option = nullptr;
    std::string text;
    bool present = false;
  };
  std::deque<Slot> slots_;  // stable addresses: CLI11 writes into text and present
  CameraParams defaults_;
  std::string cameraFile_;
  std::vector<std::string> images_;
};

/// The camera of a command: `given` over `defaults`, checked by the schema. With no --eye it
/// frames the world box [lo, hi] (looks at the centre from above and in front, far enough
/// for the bounding sphere to fill 80% of the vertical field of view); with --eye but neither
/// --at nor --dir it looks at the box's centre. Throws Error naming the flags.
CameraParams resolveCommandCamera(const ParamSet& given, const CameraParams& defaults,
                                  const glm::dvec3& lo, const glm::dvec3& hi);

/// A command's scene and camera: loads the meshes, frames the command-line camera on their
/// bounds (resolveCommandCamera) and builds the BVH (culled for that camera with --cull).
LoadedScene loadSceneForCamera(const Device& device, const SceneOptions& scene,
                               const ParamSet& given, const CameraParams& defaults, bool quiet,
                               CameraParams& camera);

}  // namespace aperture::app
