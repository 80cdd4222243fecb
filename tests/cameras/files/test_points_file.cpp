// 3D points files (cameras/files/points_file.h): COLMAP points3D.txt and .bin written here from
// COLMAP's documented layout (tracks included), a COLMAP folder, PLY vertices (ASCII float with
// faces, binary double without), NumPy .npy float32 / float64 with headers written by hand;
// the errors name the file and the entry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "cameras/files/points_file.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::errorOf;

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // x86-64 is little-endian, as the files
  out.append(bytes, sizeof(T));
}

struct Observation {
  uint32_t image;
  uint32_t point2D;
};

struct Point {
  uint64_t id;
  glm::dvec3 xyz;
  std::vector<Observation> track;
};

/// Ids out of order, a point without a track, coordinates that float32 cannot hold.
const std::vector<Point>& points() {
  static const std::vector<Point> p = {
      {5, {1.5, -2.0, 0.1}, {{7, 0}, {3, 11}}},
      {9, {1000.0, 1e-7, -7.25}, {}},
      {2, {-0.3, 42.0, 1e6 + 0.2}, {{12, 4}}},
  };
  return p;
}

std::string pointsText() {
  std::ostringstream s;
  s.precision(17);
  s << "# 3D point list with one line of data per point:\n"
    << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
    << "# Number of points: 3, mean track length: 1\n";
  for (const Point& p : points()) {
    s << p.id << ' ' << p.xyz.x << ' ' << p.xyz.y << ' ' << p.xyz.z << " 255 128 0 0.5";
    for (const Observation& o : p.track) s << ' ' << o.image << ' ' << o.point2D;
    s << '\n';
  }
  return s.str();
}

std::string pointsBinary() {
  std::string b;
  put<uint64_t>(b, points().size());
  for (const Point& p : points()) {
    put<uint64_t>(b, p.id);
    for (int a = 0; a < 3; ++a) put<double>(b, p.xyz[a]);
    put<uint8_t>(b, 10);
    put<uint8_t>(b, 20);
    put<uint8_t>(b, 30);
    put<double>(b, 0.75);
    put<uint64_t>(b, p.track.size());
    for (const Observation& o : p.track) {
      put<uint32_t>(b, o.image);
      put<uint32_t>(b, o.point2D);
    }
  }
  return b;
}

void expectColmapPoints(const PointsFile& f) {
  ASSERT_EQ(f.positions.size(), points().size());
  ASSERT_TRUE(f.hasTracks());
  std::vector<uint64_t> indptr = {0};
  std::vector<uint32_t> images;
  for (size_t k = 0; k < points().size(); ++k) {
    EXPECT_EQ(f.positions[k], points()[k].xyz) << k;
    EXPECT_EQ(f.pointIds[k], points()[k].id);
    for (const Observation& o : points()[k].track) images.push_back(o.image);
    indptr.push_back(images.size());
  }
  EXPECT_EQ(f.trackIndptr, indptr);
  EXPECT_EQ(f.trackImageIds, images);
}

TEST(PointsFile, ColmapTextAndBinary) {
  const std::string dir = test::scratchDir();
  test::writeFile(dir + "/points3D.txt", pointsText());
  test::writeFile(dir + "/model.bin", pointsBinary());
  const PointsFile text = readPointsFile(dir + "/points3D.txt");
  EXPECT_EQ(text.format, PointsFormat::ColmapText);
  EXPECT_EQ(text.path, dir + "/points3D.txt");
  expectColmapPoints(text);
  const PointsFile binary = readPointsFile(dir + "/model.bin");
  EXPECT_EQ(binary.format, PointsFormat::ColmapBinary);
  expectColmapPoints(binary);
}

TEST(PointsFile, FolderPrefersTheBinary) {
  const std::string dir = test::scratchDir();
  test::writeFile(dir + "/points3D.txt", "1 0 0 0 0 0 0 0\n");
  test::writeFile(dir + "/points3D.bin", pointsBinary());
  const PointsFile both = readPointsFile(dir);
  EXPECT_EQ(both.format, PointsFormat::ColmapBinary);
  EXPECT_EQ(std::filesystem::path(both.path).filename(), "points3D.bin");
  expectColmapPoints(both);

  std::filesystem::remove(dir + "/points3D.bin");
  const PointsFile text = readPointsFile(dir);
  EXPECT_EQ(text.format, PointsFormat::ColmapText);
  EXPECT_EQ(text.positions, std::vector<glm::dvec3>{glm::dvec3(0.0)});

  std::filesystem::remove(dir + "/points3D.txt");
  EXPECT_NE(errorOf([&] { readPointsFile(dir); }).find("points3D"), std::string::npos);
}

TEST(PointsFile, PlyAsciiFloatWithFacesAndBinaryDoubleWithout) {
  const std::string dir = test::scratchDir();
  // Values float32 holds exactly; an extra vertex property and a face to skip.
  test::writeFile(dir + "/a.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property float z\nproperty uchar red\nelement face 1\n"
                  "property list uchar int vertex_indices\nend_header\n"
                  "0.5 -2.25 3 255\n1 2 4 0\n-8 0.125 1e3 7\n3 0 1 2\n");
  const PointsFile ascii = readPointsFile(dir + "/a.ply");
  EXPECT_EQ(ascii.format, PointsFormat::Ply);
  EXPECT_FALSE(ascii.hasTracks());
  EXPECT_EQ(ascii.positions,
            (std::vector<glm::dvec3>{{0.5, -2.25, 3}, {1, 2, 4}, {-8, 0.125, 1e3}}));

  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\n"
      "property double y\nproperty double z\nend_header\n";
  for (const Point& p : points())
    for (int a = 0; a < 3; ++a) put<double>(binary, p.xyz[a]);
  test::writeFile(dir + "/b.ply", binary);
  const PointsFile doubles = readPointsFile(dir + "/b.ply");
  ASSERT_EQ(doubles.positions.size(), 3u);
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(doubles.positions[k], points()[k].xyz) << k;

  test::writeFile(dir + "/noz.ply",
                  "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                  "end_header\n1 2\n");
  const std::string message = errorOf([&] { readPointsFile(dir + "/noz.ply"); });
  EXPECT_NE(message.find(dir + "/noz.ply"), std::string::npos) << message;
  EXPECT_NE(message.find("'z'"), std::string::npos) << message;
}

/// An .npy of `descr` and shape (rows, cols), the header written out by hand (format 1.0, the
/// dict padded with spaces to a multiple of 64 bytes in all, ending in '\n').
std::string npyFile(const std::string& descr, int rows, int cols, const std::string& data) {
  std::string dict = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': (" +
                     std::to_string(rows) + ", " + std::to_string(cols) + "), }";
  while ((10 + dict.size() + 1) % 64 != 0) dict += ' ';
  dict += '\n';
  std::string out("\x93NUMPY\x01\x00", 8);
  put<uint16_t>(out, uint16_t(dict.size()));
  return out + dict + data;
}

TEST(PointsFile, NpyFloat32AndFloat64) {
  const std::string dir = test::scratchDir();
  std::string f4, f8;
  const std::vector<float> singles = {0.5f, -1.25f, 3.0f, 1e-3f, 7.0f, -9.5f};
  for (float v : singles) put<float>(f4, v);
  for (const Point& p : points())
    for (int a = 0; a < 3; ++a) put<double>(f8, p.xyz[a]);
  test::writeFile(dir + "/f4.npy", npyFile("<f4", 2, 3, f4));
  test::writeFile(dir + "/f8.npy", npyFile("<f8", 3, 3, f8));
  const PointsFile a = readPointsFile(dir + "/f4.npy");
  EXPECT_EQ(a.format, PointsFormat::Npy);
  ASSERT_EQ(a.positions.size(), 2u);
  for (size_t k = 0; k < 2; ++k)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(a.positions[k][c], double(singles[3 * k + size_t(c)]));
  const PointsFile b = readPointsFile(dir + "/f8.npy");
  ASSERT_EQ(b.positions.size(), 3u);
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(b.positions[k], points()[k].xyz);
}

/// The message of readPointsFile(path); each of `parts` must be in it.
void expectError(const std::string& path, const std::vector<std::string>& parts) {
  const std::string message = errorOf([&] { readPointsFile(path); });
  ASSERT_FALSE(message.empty()) << path << " was read";
  EXPECT_NE(message.find(path), std::string::npos) << message;
  for (const std::string& part : parts)
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

TEST(PointsFile, ErrorsNameTheFileAndTheEntry) {
  const std::string dir = test::scratchDir();
  // Truncated inside the last point's track: its length checked against the bytes left.
  const std::string full = pointsBinary();
  test::writeFile(dir + "/cut.bin", full.substr(0, full.size() - 4));
  expectError(dir + "/cut.bin", {"track length of point 2", "remaining 4 bytes"});
  // The point count checked against the bytes left (51 at least per point) before reading.
  test::writeFile(dir + "/cut2.bin", full.substr(0, 8 + 8 + 12));
  expectError(dir + "/cut2.bin", {"number of points is 3", "remaining 20 bytes"});
  // Bytes after the last point.
  test::writeFile(dir + "/long.bin", full + "x");
  expectError(dir + "/long.bin", {"1 bytes after the last of the 3 points"});
  // A count larger than the file could hold.
  std::string huge = full;
  huge[7] = 0x10;
  test::writeFile(dir + "/huge.bin", huge);
  expectError(dir + "/huge.bin", {"number of points"});

  test::writeFile(dir + "/short.txt", "# comment\n5 1 2 3 255 0 0\n");
  expectError(dir + "/short.txt", {"line 2", "7 columns"});
  test::writeFile(dir + "/odd.txt", "5 1 2 3 255 0 0 0.5 7\n");
  expectError(dir + "/odd.txt", {"line 1", "9 columns"});
  test::writeFile(dir + "/nan.txt", "\n5 1 nan 3 255 0 0 0.5\n");
  expectError(dir + "/nan.txt", {"line 2", "point 5", "not finite"});
  test::writeFile(dir + "/bad.txt", "5 1 2 3 255 0 0 0.5 7 x\n");
  expectError(dir + "/bad.txt", {"line 1", "POINT2D_IDX", "'x'"});

  std::string two;
  for (int k = 0; k < 4; ++k) put<double>(two, k);
  test::writeFile(dir + "/two.npy", npyFile("<f8", 2, 2, two));
  expectError(dir + "/two.npy", {"(2, 2)", "(N, 3)"});
  test::writeFile(dir + "/int.npy", npyFile("<i4", 1, 3, std::string(12, '\0')));
  expectError(dir + "/int.npy", {"'<i4'"});
  test::writeFile(dir + "/shortdata.npy", npyFile("<f8", 2, 3, two));
  expectError(dir + "/shortdata.npy", {"32 data bytes"});

  test::writeFile(dir + "/p.xyz", "1 2 3\n");
  expectError(dir + "/p.xyz", {"'.xyz'", ".txt, .bin, .ply, .npy"});
  test::writeFile(dir + "/p.nyp", "");
  expectError(dir + "/p.nyp", {"did you mean '.npy'"});
}

}  // namespace
}  // namespace aperture
