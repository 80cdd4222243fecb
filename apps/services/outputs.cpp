#include "apps/services/outputs.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

#include "cameras/registry/registry.h"
#include "core/io/dataset_image.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/number_text.h"

namespace aperture::app {

namespace fs = std::filesystem;

namespace {

std::string extensionList(OutputKind kind) { return join(supportedExtensions(kind), " "); }

/// "NAME: 'PATH': " — how every message of this module starts.
std::string prefix(const std::string& name, const std::string& path) {
  return cat(name, ": '", path, "': ");
}

/// The path itself when it exists, else its nearest existing ancestor ("." for a relative
/// path none of whose components exist).
fs::path nearestExisting(const fs::path& dir) {
  fs::path p = dir;
  std::error_code ec;
  while (!p.empty() && !fs::exists(fs::symlink_status(p, ec))) p = p.parent_path();
  return p.empty() ? fs::path(".") : p;
}

/// Z = dot(corner − eye, view axis) over the box's corners, for one camera: updates lo, hi.
void extendDepthRange(const WorldView& c, const glm::dvec3& boxLo, const glm::dvec3& boxHi,
                      double& lo, double& hi) {
  const glm::dvec3 axis = -c.w;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 corner(k & 1 ? boxHi.x : boxLo.x, k & 2 ? boxHi.y : boxLo.y,
                            k & 4 ? boxHi.z : boxLo.z);
    const double z = glm::dot(corner - c.eye, axis);
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  }
}

}  // namespace

const std::vector<std::string>& supportedExtensions(OutputKind kind) {
  static const std::vector<std::string> exr = {".exr"};
  static const std::vector<std::string> visibility = {".npz", ".ply"};
  static const std::vector<std::string> query = {".npz"};
  switch (kind) {
    case OutputKind::Exr:
      return exr;
    case OutputKind::Preview:
      return previewExtensions();
    case OutputKind::Visibility:
      return visibility;
    case OutputKind::Query:
      return query;
    case OutputKind::Dataset:
      break;
  }
  return datasetExtensions();
}

void checkOutputName(const std::string& name, const std::string& path, OutputKind kind) {
  if (path.empty()) throw Error(cat(name, ": empty path"));
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw Error(prefix(name, path) + "is a directory");
  if (path.back() == '/')
    throw Error(prefix(name, path) + "is a directory name (ends in '/'), not a file name");
  const std::string ext = lowerExtension(path);
  const std::vector<std::string>& known = supportedExtensions(kind);
  if (std::find(known.begin(), known.end(), ext) != known.end()) return;
  const std::string what = ext.empty() ? "has no extension" : cat("unknown extension '", ext, "'");
  const std::string hint =
      kind == OutputKind::Exr
          ? cat(" (8-bit images are written as previews; one AOV as a dataset file: ",
                extensionList(OutputKind::Dataset), ")")
          : "";
  throw Error(prefix(name, path) + what + "; supported: " + extensionList(kind) + hint);
}

void checkOutputDirectory(const std::string& name, const std::string& path,
                          const std::string& dir) {
  fs::path target = fs::path(dir.empty() ? "." : dir).lexically_normal();
  if (!target.has_filename() && target.has_parent_path()) target = target.parent_path();
  const fs::path existing = nearestExisting(target);
  std::error_code ec;
  if (!fs::is_directory(existing, ec))
    throw Error(prefix(name, path) + cat("cannot create directory '", target.string(), "': '",
                                         existing.string(), "' is not a directory"));
  if (::access(existing.c_str(), W_OK | X_OK) != 0) {
    const std::string reason = std::strerror(errno);
    const std::string what =
        existing == target
            ? cat("directory '", target.string(), "' is not writable")
            : cat("cannot create directory '", target.string(), "' in '", existing.string(), "'");
    throw Error(prefix(name, path) + what + ": " + reason);
  }
}

void checkOutputPath(const std::string& name, const std::string& path, OutputKind kind) {
  checkOutputName(name, path, kind);
  const std::string parent = fs::path(path).parent_path().string();
  checkOutputDirectory(name, path, parent.empty() ? "." : parent);
}

std::string patternDirectory(const std::string& pattern) {
  const std::string fixed = pattern.substr(0, pattern.find('{'));
  const size_t slash = fixed.rfind('/');
  return slash == std::string::npos ? "." : fixed.substr(0, slash + 1);
}

void checkDatasetOutput(const std::string& name, const std::string& path, const std::string& aov) {
  const std::optional<DatasetFormat> format = datasetFormatOf(path);
  if (!format) throw Error(prefix(name, path) + "is not a dataset file name");
  try {
    checkDatasetAov(*format, aov);
  } catch (const Error& e) {
    throw Error(prefix(name, path) + e.what());
  }
}

void checkDepthScale(const std::string& name, double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale))
    throw Error(cat(name, ": ", scale,
                    " must be positive and finite (units per scene unit: 1000 for millimetres "
                    "per metre)"));
}

void checkPreviewable(const std::string& name, const std::string& path, AovMask aovs) {
  if (previewableAovs(aovs)) return;
  throw Error(prefix(name, path) +
              cat("none of the AOVs ", aovListString(aovs),
                  " can be previewed (previewable: ", aovListString(previewableAovMask()), ")"));
}

void checkPreviewRange(const glm::dvec2& range) {
  if (!std::isfinite(range.x) || !std::isfinite(range.y))
    throw Error("NEAR and FAR must be finite");
  if (range.x < 0) throw Error(cat("NEAR ", range.x, " must be >= 0"));
  if (!(range.x < range.y)) throw Error(cat("NEAR ", range.x, " must be less than FAR ", range.y));
}

glm::dvec2 parsePreviewRange(const std::string& flag, const std::string& text) {
  const glm::dvec2 range = parseVec2(flag, text);
  try {
    checkPreviewRange(range);
  } catch (const Error& e) {
    throw Error(cat(flag, ": '", text, "': ", e.what()));
  }
  return range;
}

std::optional<glm::dvec2> depthRangeOfBox(const glm::dvec3& lo, const glm::dvec3& hi,
                                          const std::vector<CameraParams>& cameras) {
  double nearZ = INFINITY, farZ = -INFINITY;
  for (const CameraParams& p : cameras)
    extendDepthRange(makeCamera(p)->worldView(), lo, hi, nearZ, farZ);
  nearZ = std::max(nearZ, 0.0);
  if (!(farZ > nearZ) || !std::isfinite(farZ)) return std::nullopt;
  return glm::dvec2(nearZ, farZ);
}

bool writesThroughImageCodec(bool preview, const std::vector<std::string>& datasetPaths) {
  return preview || std::any_of(datasetPaths.begin(), datasetPaths.end(), [](const std::string& p) {
           const std::optional<DatasetFormat> format = datasetFormatOf(p);
           return format && encodedByImageCodec(*format);
         });
}

}  // namespace aperture::app
