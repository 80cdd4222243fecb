#pragma once
// 3D points for `aperture visibility --points P` and Python's point_visibility: a COLMAP
// points3D.txt / points3D.bin (or the model folder holding one), a PLY's vertices, or a NumPy
// .npy of shape (N, 3) (float32 or float64).
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

namespace aperture {

enum class PointsFormat { ColmapText, ColmapBinary, Ply, Npy };
const char* pointsFormatName(PointsFormat f);

struct PointsFile {
  std::string path;  ///< the file read (inside the folder when a COLMAP folder was given)
  PointsFormat format = PointsFormat::Npy;
  std::vector<glm::dvec3> positions;  ///< world coordinates, as the file holds them
  /// COLMAP only: POINT3D_ID of each point, and its track as CSR rows: the observations of
  /// point p are trackImageIds[trackIndptr[p] .. trackIndptr[p + 1]) (COLMAP IMAGE_IDs, in
  /// file order). Empty for the other formats.
  std::vector<uint64_t> pointIds;
  std::vector<uint64_t> trackIndptr;
  std::vector<uint32_t> trackImageIds;
  bool hasTracks() const { return !trackIndptr.empty(); }
};

/// Reads PATH by its name: a folder (its points3D.bin, else points3D.txt), *.txt (COLMAP
/// text), *.bin (COLMAP binary), *.ply (the vertex element's x, y, z; faces ignored), *.npy.
/// Throws Error naming the file and the line, point id or byte offset for anything malformed:
/// a truncated binary, a wrong column count, a non-finite coordinate, an .npy that is not
/// (N, 3) float32/float64 little-endian C order, a PLY without x, y, z.
PointsFile readPointsFile(const std::string& path);

}  // namespace aperture
