#include "apps/batch/resume.h"

#include <algorithm>
#include <filesystem>

#include "cameras/registry/registry.h"
#include "core/exr/exr.h"
#include "core/exr/exr_deep.h"
#include "core/io/image_codec.h"
#include "core/util/error.h"

namespace aperture::app {

namespace {

namespace fs = std::filesystem;

std::string show(const glm::dvec3& v) { return cat("(", v.x, ", ", v.y, ", ", v.z, ")"); }

std::string joined(const std::vector<std::string>& items) { return join(items, ","); }

/// "" when `file` and `job` are equal, else "<what> <file>, job wants <job>".
template <typename T>
std::string differs(const char* what, const T& file, const T& job) {
  return file == job ? "" : cat(what, " ", file, ", job wants ", job);
}

std::string differsVec(const char* what, const glm::dvec3& file, const glm::dvec3& job) {
  return file == job ? "" : cat(what, " ", show(file), ", job wants ", show(job));
}

/// The camera extras as sorted "name=value" items (files return them sorted by name), without
/// the counted ones (isCountedExtra): they follow from the lens and size compared elsewhere.
std::vector<std::string> sortedExtras(const CameraDescription& c) {
  std::vector<std::string> items;
  for (const auto& [name, value] : c.extra)
    if (!isCountedExtra(name)) items.push_back(name + "=" + value);
  std::sort(items.begin(), items.end());
  return items;
}

/// A calibrated camera's lens as text, "OPENCV fx=38 fy=39 ... (half-integer pixel centres)";
/// "none" for the other cameras.
std::string lensText(const std::optional<LensProjection>& lens) {
  if (!lens) return "none";
  std::vector<std::string> items{lens->model};
  for (size_t k = 0; k < lens->params.size() && k < lens->paramNames.size(); ++k)
    items.push_back(cat(lens->paramNames[k], "=", lens->params[k]));
  items.push_back(cat("(", lens->pixelCentre, " pixel centres)"));
  return join(items, " ");
}

/// "" when both lenses are equal (model, parameters compared exactly, pixel convention), else
/// "lens <file>, job wants <job>". The extras hold only the valid region, which distortion
/// coefficients can change without changing it (the tangential ones never do).
std::string differsLens(const std::optional<LensProjection>& file,
                        const std::optional<LensProjection>& job) {
  const bool same =
      file.has_value() == job.has_value() &&
      (!file || (file->model == job->model && file->params == job->params &&
                 file->paramNames == job->paramNames && file->pixelCentre == job->pixelCentre));
  return same ? "" : cat("lens ", lensText(file), ", job wants ", lensText(job));
}

/// Size, channels and camera of the EXR header against the job; "" when they match.
std::string headerMismatch(const Job& job, const JobImage& image) {
  ExrHeader header;
  try {
    header = readExrHeader(image.output);
  } catch (const Error& e) {
    return cat("unreadable EXR (", e.what(), ")");
  }
  const CameraParams& p = image.params;
  if (header.width != p.width || header.height != p.height)
    return cat("size ", header.width, "x", header.height, ", job wants ", p.width, "x", p.height);
  std::vector<std::string> want = exrChannelNames(job.aovs, job.exr), have = header.channels;
  std::sort(want.begin(), want.end());
  std::sort(have.begin(), have.end());
  if (have != want) return cat("channels ", joined(have), ", job wants ", joined(want));
  // World-space attributes only, so the scene's render origin plays no part.
  const CameraDescription wanted = makeCamera(p)->describeWithoutCounts();
  const std::string camera = cameraDifference(header.meta.camera, wanted);
  return camera.empty() ? "" : "camera " + camera;
}

/// "" when the preview exists, decodes and has the image's size; else why not.
std::string previewMismatch(const JobImage& image) {
  const std::string& path = image.preview;
  if (!fs::exists(path)) return cat("preview ", path, " is missing");
  ImageFileInfo info;
  std::vector<unsigned char> pixels;
  std::string error;
  const bool decoded = imageCodec().read(path, SampleType::UInt8, info, &pixels, error);
  if (info.width == 0) return cat("preview ", path, " is unreadable (", error, ")");
  if (info.width != image.params.width || info.height != image.params.height)
    return cat("preview size ", info.width, "x", info.height, ", job wants ", image.params.width,
               "x", image.params.height);
  if (!decoded) return cat("preview ", path, " does not decode (", error, ")");
  return "";
}

/// "" when the job keeps its layers in a deep file (--deep) and the image's deep file is
/// complete: every sample decodes and it holds the job's number of layers; else why not.
std::string deepMismatch(const Job& job, const JobImage& image) {
  if (!job.exr.layersInDeepFile || job.aovs.layers == 0) return "";
  const std::string path = deepLayersPath(image.output);
  if (!fs::exists(path)) return cat("deep file ", path, " is missing");
  try {
    const Framebuffer layers = readDeepLayersExr(path);
    if (layers.width != image.params.width || layers.height != image.params.height)
      return cat("deep file size ", layers.width, "x", layers.height, ", job wants ",
                 image.params.width, "x", image.params.height);
    if (layers.layers != job.aovs.layers)
      return cat("deep file ", layers.layers, " layers, job wants ", job.aovs.layers);
  } catch (const Error& e) {
    return cat("deep file unreadable (", e.what(), ")");
  }
  return "";
}

/// "" when every dataset file of the image exists (they are written atomically, so one that
/// exists is complete); else the first one missing.
std::string datasetMismatch(const JobImage& image) {
  std::error_code ec;
  for (const DatasetOutput& d : image.datasets)
    if (!fs::exists(d.path, ec)) return cat(d.aov, " file ", d.path, " is missing");
  return "";
}

}  // namespace

OutputCheck checkOutput(const Job& job, const JobImage& image) {
  std::error_code ec;
  // Without an EXR the main file is the first dataset file; it alone decides Missing.
  if (!fs::exists(image.output, ec)) return {OutputCheck::State::Missing, ""};
  std::string reason;
  if (job.writesExr) {
    reason = headerMismatch(job, image);
    if (reason.empty() && !isCompleteExr(image.output))
      reason = "incomplete EXR (truncated: not every scanline decodes)";
    if (reason.empty()) reason = deepMismatch(job, image);
  }
  if (reason.empty()) reason = datasetMismatch(image);
  if (reason.empty() && !image.preview.empty()) reason = previewMismatch(image);
  if (reason.empty()) return {OutputCheck::State::Reusable, ""};
  return {OutputCheck::State::Stale, reason};
}

std::string cameraDifference(const CameraDescription& file, const CameraDescription& job) {
  const std::string differences[] = {
      differs("type", file.type, job.type),
      differsVec("eye", file.eye, job.eye),
      differsVec("U", file.u, job.u),
      differsVec("V", file.v, job.v),
      differsVec("W", file.w, job.w),
      differs("d", file.d, job.d),
      differs("viewport", cat(file.vw, "x", file.vh), cat(job.vw, "x", job.vh)),
      differs("spp", file.spp, job.spp),
      differs("extras", joined(sortedExtras(file)), joined(sortedExtras(job))),
      differsLens(file.lens, job.lens),
  };
  for (const std::string& d : differences)
    if (!d.empty()) return d;
  return "";
}
}  // namespace aperture::app
