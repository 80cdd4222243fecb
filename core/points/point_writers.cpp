// The point-cloud formats' dispatch, PLY and PCD. LAS is in las_writer.cpp, KITTI in
// kitti_writer.cpp, the range images in range_image_writer.cpp.
#include "core/points/point_writers.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/io/atomic_file.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {

/// PLY's original type names (every reader knows them).
const char* plyTypeName(PointType type) {
  switch (type) {
    case PointType::UInt8:
      return "uchar";
    case PointType::UInt16:
      return "ushort";
    case PointType::UInt32:
      return "uint";
    case PointType::Float32:
      return "float";
    case PointType::Float64:
      return "double";
  }
  return "float";
}

/// PCD's TYPE letter.
char pcdTypeLetter(PointType type) {
  return type == PointType::Float32 || type == PointType::Float64 ? 'F' : 'U';
}

/// A field or comment that a text header line can hold: printable ASCII without spaces.
void checkPlainName(const std::string& path, const std::string& name) {
  bool plain = !name.empty();
  for (char c : name) plain = plain && c > 0x20 && c < 0x7f;
  if (!plain)
    throw Error(cat("cannot write '", path, "': point field name '", name,
                    "' is empty or holds spaces or non-ASCII bytes"));
}

void checkComment(const std::string& path, const std::string& comment) {
  if (comment.find('\n') != std::string::npos || comment.find('\r') != std::string::npos)
    throw Error(cat("cannot write '", path, "': a header comment holds a line break"));
}

/// The points as records: each point's fields one after the other, in field order (PLY's
/// binary vertex element and PCD's binary data are both this; x86 and every supported host
/// are little-endian, which PLY's binary_little_endian and PCD's binary data are).
std::vector<unsigned char> interleaved(const PointCloud& cloud) {
  size_t record = 0;
  for (const PointField& f : cloud.fields) record += pointTypeSize(f.type);
  std::vector<unsigned char> out(record * cloud.size);
  size_t at = 0;
  for (const PointField& f : cloud.fields) {
    const size_t item = pointTypeSize(f.type);
    const unsigned char* in = f.bytes.data();
    unsigned char* o = out.data() + at;
    for (size_t i = 0; i < cloud.size; ++i) std::memcpy(o + i * record, in + i * item, item);
    at += item;
  }
  return out;
}

}  // namespace

std::vector<std::string> pointFormatExtensions() {
  return {".ply", ".pcd", ".las", ".bin", ".npz", ".exr"};
}

PointFormat pointFormatOf(const std::string& path) {
  const std::string ext = toLowerAscii(std::filesystem::path(path).extension().string());
  if (ext == ".ply") return PointFormat::Ply;
  if (ext == ".pcd") return PointFormat::Pcd;
  if (ext == ".las") return PointFormat::Las;
  if (ext == ".bin") return PointFormat::KittiBin;
  if (ext == ".npz") return PointFormat::Npz;
  if (ext == ".exr") return PointFormat::Exr;
  throw Error(cat("'", path, "': unknown scan format '", ext,
                  "' (known: ", join(pointFormatExtensions(), " "), ")"));
}

bool isRangeImageFormat(PointFormat format) {
  return format == PointFormat::Npz || format == PointFormat::Exr;
}

void writePointCloud(const std::string& path, const PointCloud& cloud,
                     const PointWriteOptions& options) {
  switch (pointFormatOf(path)) {
    case PointFormat::Ply:
      return writePointsPly(path, cloud, options);
    case PointFormat::Pcd:
      return writePointsPcd(path, cloud, options);
    case PointFormat::Las:
      return writePointsLas(path, cloud, options);
    case PointFormat::KittiBin:
      return writePointsKitti(path, cloud, options);
    case PointFormat::Npz:
    case PointFormat::Exr:
      break;
  }
  throw Error(cat("cannot write '", path, "': a range-image format, not a point cloud"));
}

void writePointsPly(const std::string& path, const PointCloud& cloud,
                    const PointWriteOptions& options) {
  cloud.check(cat("cannot write '", path, "'"));
  std::string header = "ply\nformat binary_little_endian 1.0\n";
  for (const std::string& c : options.comments) {
    checkComment(path, c);
    header += cat("comment ", c, "\n");
  }
  header += cat("element vertex ", cloud.size, "\n");
  for (const PointField& f : cloud.fields) {
    checkPlainName(path, f.name);
    header += cat("property ", plyTypeName(f.type), " ", f.name, "\n");
  }
  header += "end_header\n";
  const std::vector<unsigned char> body = interleaved(cloud);
  writePiecesAtomically(path, {{header.data(), header.size()}, {body.data(), body.size()}});
}

void writePointsPcd(const std::string& path, const PointCloud& cloud,
                    const PointWriteOptions& options) {
  cloud.check(cat("cannot write '", path, "'"));
  if (cloud.fields.empty()) throw Error(cat("cannot write '", path, "': no point field"));
  std::string fields = "FIELDS", sizes = "SIZE", types = "TYPE", counts = "COUNT";
  for (const PointField& f : cloud.fields) {
    checkPlainName(path, f.name);
    fields += " " + f.name;
    sizes += cat(" ", pointTypeSize(f.type));
    types += cat(" ", pcdTypeLetter(f.type));
    counts += " 1";
  }
  std::string header = "# .PCD v0.7 - Point Cloud Data file format\n";
  for (const std::string& c : options.comments) {
    checkComment(path, c);
    header += cat("# ", c, "\n");
  }
  header +=
      cat("VERSION 0.7\n", fields, "\n", sizes, "\n", types, "\n", counts, "\nWIDTH ", cloud.size,
          "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS ", cloud.size, "\nDATA binary\n");
  const std::vector<unsigned char> body = interleaved(cloud);
  writePiecesAtomically(path, {{header.data(), header.size()}, {body.data(), body.size()}});
}

bool PointFieldSelection::selects(const std::string& name) const {
  return everyField || std::find(names.begin(), names.end(), name) != names.end() ||
         (faceProperties && !isStandardPointField(name));
}

void PointFieldSelection::add(const PointFieldSelection& other) {
  everyField = everyField || other.everyField;
  faceProperties = faceProperties || other.faceProperties;
  for (const std::string& name : other.names)
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
}

PointFieldSelection pointFieldsWrittenAs(PointFormat format, const PointWriteOptions& options) {
  namespace pf = point_fields;
  PointFieldSelection s;
  s.everyField = false;
  switch (format) {
    case PointFormat::Ply:
    case PointFormat::Pcd:
      s.everyField = true;
      break;
    case PointFormat::Las:
      s.names = {
          pf::kX,      pf::kY, pf::kZ, pf::kIntensity, pf::kTime, pf::kRing, pf::kReturnNumber,
          pf::kReturns};
      break;
    case PointFormat::KittiBin:
      s.names = {pf::kX, pf::kY, pf::kZ, pf::kIntensity, pf::kInstance};
      break;
    case PointFormat::Npz:
    case PointFormat::Exr:
      s.names = {pf::kRing, pf::kColumn, pf::kRange,  pf::kIntensity, pf::kIncidence, pf::kX,
                 pf::kY,    pf::kZ,      pf::kPrimId, pf::kGeomId,    pf::kInstance};
      s.faceProperties = true;
      break;
  }
  if (!options.labelField.empty()) s.names.push_back(options.labelField);
  return s;
}

}  // namespace aperture
