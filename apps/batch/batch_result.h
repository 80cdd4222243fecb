#pragma once
// `aperture batch`: the outcome of one job image in this run (rendered, skipped by --resume,
// failed, interrupted), shared by the render loop, the writer, progress and the summary.
#include <cstdint>
#include <map>
#include <string>

#include "apps/jobs/job.h"
#include "core/util/error.h"

namespace aperture::app {

enum class ImageStatus { Pending, Ok, Failed, Skipped, Interrupted };

/// The summary's name of a status: pending ok failed skipped interrupted.
inline const char* imageStatusName(ImageStatus s) {
  switch (s) {
    case ImageStatus::Pending:
      return "pending";
    case ImageStatus::Ok:
      return "ok";
    case ImageStatus::Failed:
      return "failed";
    case ImageStatus::Skipped:
      return "skipped";
    case ImageStatus::Interrupted:
      return "interrupted";
  }
  return "?";
}

/// One image of the job that this run (its shard) is responsible for.
struct ImageResult {
  const JobImage* image = nullptr;
  ImageStatus status = ImageStatus::Pending;
  std::string error;  ///< why it failed
  /// With --resume, why an existing output was not reused ("" when reused or absent).
  std::string staleReason;
  double renderSeconds = 0, writeSeconds = 0;
  uint64_t rays = 0;
  /// With the job's "id_counts": per id AOV (geomid, face.*, vertex.*), pixels per id.
  std::map<std::string, std::map<uint32_t, uint64_t>> idCounts;
  double mrays() const { return renderSeconds > 0 ? double(rays) / renderSeconds * 1e-6 : 0; }
};

/// "camera frame N": the camera's name and the frame number along its path.
inline std::string imageLabel(const JobImage& image) {
  return cat(image.camera, " frame ", image.frame);
}

}  // namespace aperture::app
