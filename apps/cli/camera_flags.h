#pragma once
// The camera flags of render, bench, camera and tradeoff, generated from the camera parameter
// schema (cameras/schema/param_schema.h); the camera they give is resolved against a scene by
// apps/services/command_camera.h.
#include <CLI/CLI.hpp>
#include <deque>
#include <string>

#include "apps/services/command_camera.h"
#include "cameras/files/camera_file.h"
#include "cameras/schema/param_schema.h"

namespace aperture::app {

class CameraFlags {
 public:
  /// Registers a flag for every camera parameter of every model, with help generated from
  /// the schema; `defaults` are the command's own (e.g. bench renders 1920x1080).
  void add(CLI::App& app, const CameraParams& defaults = {});
  /// What the command line gave (call after parsing), each value with its flag as source.
  /// With --cameras, the parameters of the one image --image names come first (from the
  /// camera file) and the flags given override them. `fileOptions`: how to read the file
  /// (the glTF scene of --gltf-scene).
  ParamSet given(const CameraFileOptions& fileOptions = {}) const;
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

}  // namespace aperture::app
