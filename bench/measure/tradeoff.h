#pragma once
// The speed/accuracy study behind `aperture tradeoff`: one knob at a time from a base
// setting, each compared with a per-scene reference (robust, high quality, camera-relative,
// many samples) and timed.
#include <string>
#include <vector>

#include "apps/services/render_options.h"
#include "apps/services/scene_setup.h"
#include "cameras/schema/params.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/exr/exr.h"
#include "core/mesh/mesh.h"

namespace aperture::app {

/// Everything one row of the study varies.
struct TradeoffSetting {
  std::string knob;   ///< "base", "bvh", "packet", "spp", "placement", "exr_color", ...
  std::string value;  ///< the knob's value as text ("low robust", "16", "world-space", ...)
  BuildOptions build;
  Placement placement = Placement::CameraRelative;
  RenderSettings render;  ///< packet, tile, spp
  ExrOptions exr;
};

/// The measurements of one setting.
struct TradeoffRow {
  TradeoffSetting setting;
  /// Color (R G B A) against the reference at the reference spp; PSNR with peak 1.0.
  double rmse = 0, psnr = 0, maxError = 0;
  /// Color RMSE against the reference settings at this row's spp: the knob's own error,
  /// without the sampling error that the spp rows measure.
  double rmseSameSpp = 0;
  /// Geometry (the centre ray of each pixel) against the reference settings at this row's spp.
  double primIdMismatch = 0, depthRelError = 0;
  double frameSeconds = 0;    ///< median over the timed frames
  double mraysPerSecond = 0;  ///< median
  double buildSeconds = 0;
  long long embreeBytes = 0;
  long long exrBytes = 0;   ///< file size with this row's EXR options
  double writeSeconds = 0;  ///< median EXR write time
  bool pareto = false;      ///< non-dominated in (frameSeconds + writeSeconds, rmse)
  double costSeconds() const { return frameSeconds + writeSeconds; }
};

struct TradeoffConfig {
  SceneOptions scene;   ///< meshes; its BVH and placement flags set the base setting
  CameraParams camera;  ///< complete (size included); spp is set per row
  RenderSettings base;  ///< base packet, tile, spp
  ExrOptions baseExr;
  int referenceSpp = 256;
  int frames = 3, warmup = 1, writes = 3;
  /// The threads each file is encoded with, as `render` and `batch` do (ExrEncodingThreads).
  int encodeThreads = 0;
  bool quick = false;        ///< fewer values per knob, no combinations
  bool combinations = true;  ///< also a few spp x BVH-quality combinations
  std::string tempDir;       ///< where the EXR knobs write their files
  bool quiet = false;
};

/// The settings of the study: the base first, then each knob's other values.
std::vector<TradeoffSetting> tradeoffSettings(const TradeoffConfig& config);

/// Runs the study. The camera's world placement comes from `config.camera` as given (the
/// caller frames the scene). Throws Error.
std::vector<TradeoffRow> runTradeoff(const TradeoffConfig& config);

/// Marks the rows not dominated in (costSeconds, rmse): no other row is at least as good in
/// both and better in one.
void markPareto(std::vector<TradeoffRow>& rows);

/// One line per row, header first; the columns are documented in bench/TRADEOFF.md.
std::string tradeoffCsv(const std::vector<TradeoffRow>& rows);
/// A Markdown table of the rows and the equal-error / equal-time summaries.
std::string tradeoffMarkdown(const std::vector<TradeoffRow>& rows, const std::string& title);

}  // namespace aperture::app
