#pragma once
// Point clouds and range images as named, typed columns: what a LiDAR scan produces
// (apps/services/scan.h) and what the writers of core/points/point_writers.h write. The
// standard fields and their units are listed in docs/lidar.md.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/util/huge_pages.h"

namespace aperture {

/// The type of one field value.
enum class PointType { UInt8, UInt16, UInt32, Float32, Float64 };
/// The NumPy dtype string of `type` ("|u1", "<u2", "<u4", "<f4", "<f8").
const char* npyDescrOf(PointType type);
size_t pointTypeSize(PointType type);

/// One field of a point cloud or one channel of a range image: `count` values of `type`,
/// stored as their native bytes (a LargeBuffer: on huge pages from 2 MB, and left unwritten by
/// a resize, so a scan's fields are touched once, by the threads that fill them).
struct PointField {
  std::string name;
  PointType type = PointType::Float32;
  LargeBuffer<unsigned char> bytes;

  size_t count() const { return bytes.size() / pointTypeSize(type); }
  /// Value `i` widened to double (exact for every type here).
  double value(size_t i) const;
  /// Value `i` as uint32 (an unsigned field; floats are truncated).
  uint32_t uintValue(size_t i) const;
  template <typename T>
  T* as() {
    return reinterpret_cast<T*>(bytes.data());
  }
  template <typename T>
  const T* as() const {
    return reinterpret_cast<const T*>(bytes.data());
  }
};

/// The standard fields a scan fills (docs/lidar.md): positions in the frame asked for (float32,
/// float64 in world coordinates), range in metres, time offset from the sweep's start in
/// integer nanoseconds, ring (index into the beam table), column (measurement id, firing
/// order), azimuth (radians), incidence cosine, primid, geomid, instance, intensity, and for
/// multiple returns the return's number (1-based) and the ray's number of returns.
namespace point_fields {
inline constexpr const char* kX = "x";
inline constexpr const char* kY = "y";
inline constexpr const char* kZ = "z";
inline constexpr const char* kRange = "range";
inline constexpr const char* kTime = "time";
inline constexpr const char* kRing = "ring";
inline constexpr const char* kColumn = "column";
inline constexpr const char* kAzimuth = "azimuth";
inline constexpr const char* kIncidence = "incidence";
inline constexpr const char* kPrimId = "primid";
inline constexpr const char* kGeomId = "geomid";
inline constexpr const char* kInstance = "instance";
inline constexpr const char* kIntensity = "intensity";
inline constexpr const char* kReturnNumber = "return_number";
inline constexpr const char* kReturns = "returns";
}  // namespace point_fields

/// Whether `name` is one of the standard fields above (else a face property's).
bool isStandardPointField(const std::string& name);

/// Points as columns: every field holds `size` values.
struct PointCloud {
  size_t size = 0;
  std::vector<PointField> fields;
  /// Trajectory time of the sweep's start, seconds: LAS's GPS time is this plus `time`.
  double startSeconds = 0;

  /// The field `name`, or nullptr.
  const PointField* find(const std::string& name) const;
  PointField* find(const std::string& name);
  /// Adds a field of `size` values (zero, or left unwritten with `zeroed` false: the caller
  /// writes every one) and returns its storage. Throws Error for a name already there.
  template <typename T>
  T* add(const std::string& name, PointType type, bool zeroed = true) {
    return addField(name, type, zeroed).as<T>();
  }
  PointField& addField(const std::string& name, PointType type, bool zeroed = true);
  /// addField(name, type, false) with `storage` as the field's buffer: its memory is reused
  /// (values left unwritten), so a cloud of the shape of the one it came from maps none anew.
  PointField& addField(const std::string& name, PointType type,
                       LargeBuffer<unsigned char>&& storage);
  /// Throws Error (naming `what`) unless every field holds `size` values and names differ.
  void check(const std::string& what) const;
};

/// A range image in the sensor's own layout: rows (beams, row 0 the beam table's first entry)
/// × columns (measurement ids, firing order: staggered as the sensor sends it). Every channel
/// holds rows × columns values, row-major; a miss holds 0.
struct RangeImage {
  int rows = 0, columns = 0;
  std::vector<PointField> channels;
  /// Ouster's pixel_shift_by_row (one per row), else empty: then no destaggered image.
  std::vector<int> pixelShiftByRow;
  const PointField* find(const std::string& name) const;
  PointField& addChannel(const std::string& name, PointType type);
};

/// The channel `staggered` (rows × columns) destaggered as ouster-sdk's destagger(info, field)
/// does: row u moves right by pixel_shift_by_row[u] columns, wrapping, so the value at column c
/// lands at column (c + shift) mod columns. With `inverse`, the other way. Units and type are
/// those of the source.
PointField destagger(const PointField& staggered, int rows, int columns,
                     const std::vector<int>& pixelShiftByRow, bool inverse = false);

}  // namespace aperture
