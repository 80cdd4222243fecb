#pragma once
// Point clouds and range images written in the formats robotics tools read, each through
// core/io/atomic_file.h (a failure leaves no file, and no partial one):
//  - .ply  binary little-endian PLY, element vertex with every field as a property;
//  - .pcd  PCL's PCD v0.7, DATA binary (FIELDS/SIZE/TYPE/COUNT as PCL reads them);
//  - .las  ASPRS LAS 1.4 (R15), point data record format 6, no VLRs;
//  - .bin  KITTI velodyne scans (float32 x y z intensity per point) and, beside it, a
//          SemanticKITTI .label (uint32: semantic label in the low 16 bits, instance in the
//          high 16);
//  - .npz  a range image, one array per channel (rows × columns);
//  - .exr  a range image, one channel per field (float32 or uint32).
#include <string>
#include <vector>

#include "core/points/point_cloud.h"

namespace aperture {

enum class PointFormat { Ply, Pcd, Las, KittiBin, Npz, Exr };

/// The format of `path` by its extension (case-insensitive). Throws Error naming the path and
/// the known extensions.
PointFormat pointFormatOf(const std::string& path);
/// The extensions pointFormatOf knows, with their dot: ".ply .pcd .las .bin .npz .exr".
std::vector<std::string> pointFormatExtensions();
/// True for the range-image formats (.npz, .exr), false for the point-cloud ones.
bool isRangeImageFormat(PointFormat format);

/// What the writers take beside the points.
struct PointWriteOptions {
  /// A uint32 field holding a semantic label (a face property, e.g. "semantic"): LAS's
  /// classification (0..255) and the low 16 bits of SemanticKITTI's label. Empty: 0.
  std::string labelField;
  /// Comment lines for the headers that have them (PLY, PCD).
  std::vector<std::string> comments;
};

/// Which fields of a cloud a file holds, so that a scan computes only those: every field, or
/// the standard fields `names` (those a cloud has) and, with `faceProperties`, every field
/// that is not a standard one.
struct PointFieldSelection {
  bool everyField = true;
  bool faceProperties = false;
  std::vector<std::string> names;

  bool selects(const std::string& name) const;
  /// The fields either selects.
  void add(const PointFieldSelection& other);
};

/// The fields a file of `format` is written from (the one owner of it, beside the writers):
/// PLY and PCD every field; LAS x y z intensity time ring return_number returns and the label
/// field; KITTI x y z intensity instance and the label field; the range images (.npz, .exr)
/// ring and column (each point's pixel), their channels range intensity incidence x y z primid
/// geomid instance and every face property.
PointFieldSelection pointFieldsWrittenAs(PointFormat format, const PointWriteOptions& options);

/// Writes `cloud` to `path` in the point-cloud format of its extension (.ply, .pcd, .las, .bin).
void writePointCloud(const std::string& path, const PointCloud& cloud,
                     const PointWriteOptions& options = {});

void writePointsPly(const std::string& path, const PointCloud& cloud,
                    const PointWriteOptions& options = {});
void writePointsPcd(const std::string& path, const PointCloud& cloud,
                    const PointWriteOptions& options = {});

/// LAS 1.4 point format 6: X Y Z as int32 with scale 0.001 (millimetres) and an offset per axis
/// at the whole metre nearest the centre of the points' box; intensity = round(65535 ·
/// clamp(intensity, 0, 1)); return number and number of returns from return_number / returns
/// (else 1 and 1); classification from the label field (Error past 255; else 0); user data the
/// ring (when ≤ 255); GPS time = startSeconds + time · 1e-9 (global encoding: GPS week time,
/// the WKT bit set as R15 asks for formats 6-10). Needs x, y, z; Error naming the file for
/// coordinates that do not fit int32 at that scale.
void writePointsLas(const std::string& path, const PointCloud& cloud,
                    const PointWriteOptions& options = {});

/// The SemanticKITTI .label path beside a KITTI .bin: the same name with ".label".
std::string kittiLabelPathOf(const std::string& binPath);
/// The .bin (float32 x y z intensity; intensity 0 without the field) and its .label (semantic
/// from the label field, instance from `instance`; Error naming the field for a value past
/// 65535). Both files are complete or neither is there.
void writePointsKitti(const std::string& path, const PointCloud& cloud,
                      const PointWriteOptions& options = {});

/// A range image as .npz: each channel an array of shape (rows, columns) of its type, and with
/// pixel shifts each channel destaggered again as "destaggered.NAME", plus the int32 array
/// "pixel_shift_by_row".
void writeRangeImageNpz(const std::string& path, const RangeImage& image);
/// A range image as EXR: each channel a FLOAT (float32, float64 narrowed) or UINT (unsigned
/// types) channel, the destaggered ones as the layer "destaggered.NAME".
void writeRangeImageExr(const std::string& path, const RangeImage& image);
/// Writes `image` in the range-image format of `path`'s extension (.npz, .exr).
void writeRangeImage(const std::string& path, const RangeImage& image);

}  // namespace aperture
