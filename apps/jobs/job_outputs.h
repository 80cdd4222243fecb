#pragma once
// The outputs of a job: its checks before any work, and the preview options its frames share.
#include <glm/glm.hpp>
#include <string>

#include "apps/jobs/job.h"
#include "apps/services/outputs.h"

namespace aperture::app {

/// The output checks of a parsed job, as `aperture render` checks --out and --preview: the
/// "output", "outputs" and "preview" patterns' extensions, that the job's AOVs can be previewed
/// when it has a preview pattern and that each "outputs" format holds its AOV,
/// checkOutputName of every frame's paths, and checkOutputDirectory of `outputDirectory`,
/// each "outputs" entry's directory and `previewDirectory` (each pattern's directory up to its
/// first placeholder, resolved; directories named by placeholders are created, or fail, per
/// frame). Throws Error("output: ...", "outputs: ..." or "preview: ...").
void checkJobOutputs(const Job& job, const std::string& outputDirectory,
                     const std::string& previewDirectory);

/// The preview options every frame of a batch uses: the job's (its "preview_range"), else,
/// when the job writes previews that show depth, the depthRangeOfBox of the scene's box
/// [lo, hi] (LoadedScene's world bounds) over every frame of the job (all shards), so that the
/// frames of a turntable share one range and shards agree. Without such a range (nothing in front
/// of any camera), each preview falls back to its own range.
PreviewOptions batchPreviewOptions(const Job& job, const glm::dvec3& lo, const glm::dvec3& hi);

}  // namespace aperture::app
