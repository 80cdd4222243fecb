// 3D points in: COLMAP's points3D (the formats of COLMAP's reconstruction_io_text.cc and
// reconstruction_io_binary.cc), a PLY's vertices and a NumPy .npy.
//
//   points3D.txt  one line per point: POINT3D_ID X Y Z R G B ERROR, then the track as
//                 IMAGE_ID POINT2D_IDX pairs (possibly none); '#' starts a comment line.
//   points3D.bin  uint64 count; per point uint64 id, float64 x y z, uint8 r g b, float64
//                 error, uint64 track length, then per observation uint32 image id and uint32
//                 point2D index. Little-endian.
//   *.ply         the vertex element's x, y, z, through the mesh loader (core/mesh/ply.cpp) with
//                 LoadOptions::verticesOnly: faces, if any, are skipped.
//   *.npy         shape (N, 3), '<f4' or '<f8', C order (the header of core/io/npy.h).
//
// Colours and errors are read and checked for shape but not kept.
#include "cameras/files/points_file.h"

#include <cmath>
#include <cstring>
#include <filesystem>

#include "cameras/files/colmap_reading.h"
#include "core/io/npy.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/little_endian.h"
#include "core/util/mapped_file.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {

namespace fs = std::filesystem;
using camera_files::BinaryReader;

/// The extensions readPointsFile reads, for messages.
const std::vector<std::string>& pointsExtensions() {
  static const std::vector<std::string> extensions = {".txt", ".bin", ".ply", ".npy"};
  return extensions;
}

void checkFinite(const glm::dvec3& p, const std::string& context) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
    throw Error(cat(context, ": coordinate (", p.x, ", ", p.y, ", ", p.z, ") is not finite"));
}

// ---- COLMAP ----

PointsFile readColmapPointsText(const std::string& path) {
  using namespace camera_files;
  PointsFile out;
  out.path = path;
  out.format = PointsFormat::ColmapText;
  out.trackIndptr.push_back(0);
  for (const auto& [number, line] : textLines(readWholeFile(path))) {
    if (!isDataLine(line)) continue;
    std::string context = cat(path, " line ", number);
    const std::vector<std::string> tok = tokensOf(line);
    if (tok.size() < 8 || tok.size() % 2 != 0)
      throw Error(cat(context, ": expected POINT3D_ID X Y Z R G B ERROR and (IMAGE_ID, ",
                      "POINT2D_IDX) pairs, got ", tok.size(), " columns"));
    const auto id = uint64_t(integerToken(tok[0], context, "POINT3D_ID", 0, INT64_MAX));
    context += cat(" (point ", id, ")");
    glm::dvec3 p;
    const char* axes[] = {"X", "Y", "Z"};
    for (int a = 0; a < 3; ++a) p[a] = numberToken(tok[1 + size_t(a)], context, axes[a]);
    checkFinite(p, context);
    const char* channels[] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) integerToken(tok[4 + size_t(c)], context, channels[c], 0, 255);
    numberToken(tok[7], context, "ERROR");
    for (size_t k = 8; k < tok.size(); k += 2) {
      out.trackImageIds.push_back(
          uint32_t(integerToken(tok[k], context, "IMAGE_ID", 0, kMaxColmapId)));
      integerToken(tok[k + 1], context, "POINT2D_IDX", 0, kMaxColmapId);
    }
    out.pointIds.push_back(id);
    out.positions.push_back(p);
    out.trackIndptr.push_back(out.trackImageIds.size());
  }
  return out;
}

PointsFile readColmapPointsBinary(const std::string& path) {
  BinaryReader in(path);
  PointsFile out;
  out.path = path;
  out.format = PointsFormat::ColmapBinary;
  out.trackIndptr.push_back(0);
  // id, xyz, rgb, error and the track length.
  const uint64_t count = in.readCount(8 + 3 * 8 + 3 + 8 + 8, "the number of points");
  out.positions.reserve(size_t(count));
  out.pointIds.reserve(size_t(count));
  for (uint64_t k = 0; k < count; ++k) {
    const auto id = in.read<uint64_t>(cat("the id of point #", k + 1));
    const std::string entry = cat("point ", id);
    glm::dvec3 p;
    for (int a = 0; a < 3; ++a) p[a] = in.read<double>(cat("the position of ", entry));
    checkFinite(p, cat(path, " (", entry, " at byte ", in.offset() - 24, ")"));
    in.skip(3, cat("the colour of ", entry));
    in.skip(8, cat("the error of ", entry));
    const uint64_t track = in.readCount(8, cat("the track length of ", entry));
    for (uint64_t t = 0; t < track; ++t) {
      out.trackImageIds.push_back(in.read<uint32_t>(cat("the track of ", entry)));
      in.skip(4, cat("the track of ", entry));  // POINT2D_IDX
    }
    out.pointIds.push_back(id);
    out.positions.push_back(p);
    out.trackIndptr.push_back(out.trackImageIds.size());
  }
  if (in.remaining() != 0)
    throw Error(cat(path, ": ", in.remaining(), " bytes after the last of the ", count,
                    " points (at byte ", in.offset(), ")"));
  return out;
}

// ---- PLY and NPY ----

PointsFile readPlyPoints(const std::string& path) {
  LoadOptions options;
  options.verticesOnly = true;
  const Mesh mesh = loadPly(path, options);
  PointsFile out;
  out.path = path;
  out.format = PointsFormat::Ply;
  out.positions.resize(mesh.vertexCount);
  // The loader keeps double coordinates in positionsDouble and float ones in positions.
  const bool fromDouble = !mesh.positionsDouble.empty();
  for (size_t k = 0; k < mesh.vertexCount; ++k) {
    for (int a = 0; a < 3; ++a)
      out.positions[k][a] = fromDouble ? mesh.positionsDouble[3 * k + size_t(a)]
                                       : double(mesh.positions[3 * k + size_t(a)]);
    checkFinite(out.positions[k], cat(path, " (vertex ", k, ")"));
  }
  return out;
}

PointsFile readNpyPoints(const std::string& path) {
  const MappedFile file(path);
  const auto* bytes = reinterpret_cast<const uint8_t*>(file.data());
  const NpyHeader h = parseNpyHeader(bytes, file.size(), path);
  if (h.descr != "<f4" && h.descr != "<f8")
    throw Error(cat(path, ": NPY dtype '", h.descr, "' (points are '<f4' or '<f8')"));
  if (h.fortranOrder) throw Error(cat(path, ": NPY array in Fortran order (C order is read)"));
  if (h.shape.size() != 2 || h.shape[1] != 3)
    throw Error(cat(path, ": NPY shape (",
                    join(h.shape, ", ", [](uint64_t d) { return std::to_string(d); }),
                    h.shape.size() == 1 ? "," : "", ") is not (N, 3)"));
  const size_t item = h.descr == "<f4" ? 4 : 8;
  const uint64_t n = h.shape[0];
  const uint64_t dataBytes = file.size() - h.dataOffset;
  if (n > dataBytes / (3 * item) || dataBytes != n * 3 * item)
    throw Error(cat(path, ": ", dataBytes, " data bytes do not hold shape (", n, ", 3) of '",
                    h.descr, "' (", 3 * item, " bytes a row)"));
  PointsFile out;
  out.path = path;
  out.format = PointsFormat::Npy;
  out.positions.resize(size_t(n));
  const char* data = file.data() + h.dataOffset;
  for (size_t k = 0; k < size_t(n); ++k) {
    for (int a = 0; a < 3; ++a) {
      const char* at = data + item * (3 * k + size_t(a));
      out.positions[k][a] =
          item == 4 ? double(loadLittleEndian<float>(at)) : loadLittleEndian<double>(at);
    }
    checkFinite(out.positions[k], cat(path, " (row ", k, ")"));
  }
  return out;
}

/// The points file of a COLMAP model folder: points3D.bin, else points3D.txt.
std::string colmapPointsIn(const std::string& dir) {
  for (const char* name : {"points3D.bin", "points3D.txt"}) {
    const fs::path p = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  throw Error(cat(dir, ": the folder holds neither points3D.bin nor points3D.txt"));
}

}  // namespace

const char* pointsFormatName(PointsFormat f) {
  switch (f) {
    case PointsFormat::ColmapText:
      return "COLMAP points3D.txt";
    case PointsFormat::ColmapBinary:
      return "COLMAP points3D.bin";
    case PointsFormat::Ply:
      return "PLY vertices";
    case PointsFormat::Npy:
      return "NumPy .npy (N, 3)";
  }
  return "unknown";
}

PointsFile readPointsFile(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return readPointsFile(colmapPointsIn(path));
  const std::string extension = lowerExtension(path);
  if (extension == ".txt") return readColmapPointsText(path);
  if (extension == ".bin") return readColmapPointsBinary(path);
  if (extension == ".ply") return readPlyPoints(path);
  if (extension == ".npy") return readNpyPoints(path);
  throw Error(cat(path, ": unknown points file extension '", extension, "'",
                  didYouMean(extension, pointsExtensions()), " (accepted: a COLMAP model folder, ",
                  join(pointsExtensions(), ", "), ")"));
}

}  // namespace aperture
