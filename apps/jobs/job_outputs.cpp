#include "apps/jobs/job_outputs.h"

#include "core/io/dataset_image.h"

namespace aperture::app {

void checkJobOutputs(const Job& job, const std::string& outputDirectory,
                     const std::string& previewDirectory) {
  if (job.writesExr) {
    checkOutputName("output", job.outputPattern, OutputKind::Exr);
    checkOutputDirectory("output", job.outputPattern, outputDirectory);
  }
  for (const JobDatasetOutput& d : job.datasets) {
    checkOutputName("outputs", d.pattern, OutputKind::Dataset);
    checkDatasetOutput("outputs", d.pattern, d.aov);
    checkOutputDirectory("outputs", d.pattern, d.directory);
  }
  const bool previews = !job.previewPattern.empty();
  if (previews) {
    checkOutputName("preview", job.previewPattern, OutputKind::Preview);
    checkPreviewable("preview", job.previewPattern, job.aovs.mask);
    checkOutputDirectory("preview", job.previewPattern, previewDirectory);
  }
  for (const JobImage& image : job.images) {
    if (job.writesExr) checkOutputName("output", image.output, OutputKind::Exr);
    for (const DatasetOutput& d : image.datasets)
      checkOutputName("outputs", d.path, OutputKind::Dataset);
    if (previews) checkOutputName("preview", image.preview, OutputKind::Preview);
  }
}

PreviewOptions batchPreviewOptions(const Job& job, const glm::dvec3& lo, const glm::dvec3& hi) {
  PreviewOptions options = job.preview;
  if (options.depthRange || job.previewPattern.empty() || previewAov(job.aovs.mask) != kAovDepth)
    return options;
  if (!(lo.x <= hi.x)) return options;
  std::vector<CameraParams> cameras;
  for (const JobImage& image : job.images) cameras.push_back(image.params);
  options.depthRange = depthRangeOfBox(lo, hi, cameras);
  return options;
}

}  // namespace aperture::app
