// KITTI velodyne scans (.bin: float32 x y z intensity per point, no header) and SemanticKITTI
// labels (.label: one uint32 per point, semantic label in the low 16 bits, instance in the
// high 16), little-endian.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/atomic_file.h"
#include "core/points/point_writers.h"
#include "core/util/error.h"
#include "core/util/little_endian.h"

namespace aperture {

std::string kittiLabelPathOf(const std::string& binPath) {
  return std::filesystem::path(binPath).replace_extension(".label").string();
}

void writePointsKitti(const std::string& path, const PointCloud& cloud,
                      const PointWriteOptions& options) {
  cloud.check(cat("cannot write '", path, "'"));
  namespace pf = point_fields;
  const PointField* xyz[3] = {cloud.find(pf::kX), cloud.find(pf::kY), cloud.find(pf::kZ)};
  for (const PointField* f : xyz)
    if (!f) throw Error(cat("cannot write '", path, "': KITTI needs the point fields x y z"));
  const PointField* intensity = cloud.find(pf::kIntensity);
  const PointField* label = nullptr;
  if (!options.labelField.empty()) {
    label = cloud.find(options.labelField);
    if (!label)
      throw Error(cat("cannot write '", path, "': no label field '", options.labelField, "'"));
  }
  const PointField* instance = cloud.find(pf::kInstance);

  std::vector<float> scan(4 * cloud.size);
  std::vector<uint32_t> labels(cloud.size);
  for (size_t i = 0; i < cloud.size; ++i) {
    for (int a = 0; a < 3; ++a) scan[4 * i + size_t(a)] = float(xyz[a]->value(i));
    scan[4 * i + 3] = intensity ? float(intensity->value(i)) : 0.0f;
    const uint32_t semantic = label ? label->uintValue(i) : 0u;
    const uint32_t object = instance ? instance->uintValue(i) : 0u;
    if (semantic > 0xFFFFu)
      throw Error(cat("cannot write '", kittiLabelPathOf(path), "': label field '",
                      options.labelField, "' is ", semantic, " at point ", i,
                      " (SemanticKITTI: 0..65535)"));
    if (object > 0xFFFFu)
      throw Error(cat("cannot write '", kittiLabelPathOf(path), "': instance ", object,
                      " at point ", i, " (SemanticKITTI: 0..65535)"));
    labels[i] = semantic | (object << 16);
  }
  std::vector<unsigned char> scanBytes(4 * scan.size()), labelBytes(4 * labels.size());
  storeLittleEndianWords(scan.data(), scan.size(), scanBytes.data());
  storeLittleEndianWords(labels.data(), labels.size(), labelBytes.data());
  // The label first, then the scan: a failure on the scan removes the label again, so both
  // files are there or neither is.
  const std::string labelPath = kittiLabelPathOf(path);
  writeBytesAtomically(labelPath, labelBytes.data(), labelBytes.size());
  try {
    writeBytesAtomically(path, scanBytes.data(), scanBytes.size());
  } catch (...) {
    std::remove(labelPath.c_str());
    throw;
  }
}

}  // namespace aperture
