// The PLY loader (core/mesh/ply.cpp): ASCII with extra properties, lists and polygons, every
// binary encoding of one reference mesh (byte orders and index types), triangle strips with
// restarts, the vertex_index name and CRLF line ends.
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::scratchDir;
using test::writeFile;

/// The reference mesh every PLY variant below encodes: 6 vertices, a quad, a pentagon, a triangle.
const std::vector<double> kReferenceVertices = {0, 0, 0, 1,   0, 0,     1,  1,   0,
                                                0, 1, 0, 0.5, 2, -1.25, -3, 4.5, 7};
const std::vector<std::vector<int>> kReferenceFaces = {{0, 1, 2, 3}, {0, 1, 4, 5, 3}, {5, 2, 1}};
// Fans: quad -> (0,1,2),(0,2,3); pentagon -> (0,1,4),(0,4,5),(0,5,3); triangle as is.
const std::vector<uint32_t> kReferenceTriangles = {0, 1, 2, 0, 2, 3, 0, 1, 4,
                                                   0, 4, 5, 0, 5, 3, 5, 2, 1};

/// Appends binary values in a chosen byte order.
struct Bytes {
  bool bigEndian = false;
  std::string s;
  template <typename T>
  void put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (bigEndian)
      for (size_t i = sizeof(T); i-- > 0;) s += b[i];
    else
      s.append(b, sizeof(T));
  }
};

std::string plyFile(const std::string& name, const std::string& bytes) {
  std::string path = scratchDir() + "/" + name;
  writeFile(path, bytes);
  return path;
}

std::vector<double> worldVertices(const Mesh& m) {
  std::vector<double> v;
  if (!m.positionsDouble.empty()) return m.positionsDouble;
  for (size_t i = 0; i < 3 * m.vertexCount; ++i) v.push_back(m.positions[i]);
  return v;
}

void expectReference(const Mesh& m, bool doubles) {
  ASSERT_EQ(m.vertexCount, 6u);
  EXPECT_EQ(!m.positionsDouble.empty(), doubles);
  std::vector<double> v = worldVertices(m);
  ASSERT_EQ(v.size(), kReferenceVertices.size());
  for (size_t i = 0; i < v.size(); ++i)
    EXPECT_EQ(v[i], kReferenceVertices[i]) << "coordinate " << i;
  EXPECT_EQ(test::asVector(m.indices), kReferenceTriangles);
  EXPECT_EQ(m.stats.sourceFaces, 3u);
}

TEST(PlyAscii, ExtraPropertiesListsAndPolygons) {
  std::ostringstream s;
  s << "ply\nformat ascii 1.0\ncomment test\nelement vertex 6\nproperty float confidence\n"
       "property float x\nproperty list uchar int neighbours\nproperty float y\n"
       "property float z\nproperty uchar red\nelement face 3\nproperty list uchar int "
       "vertex_indices\nproperty int flags\nend_header\n";
  for (int i = 0; i < 6; ++i)
    s << "0.5 " << kReferenceVertices[3 * i] << " 2 7 8 " << kReferenceVertices[3 * i + 1] << " "
      << kReferenceVertices[3 * i + 2] << " 255\n";
  for (const auto& f : kReferenceFaces) {
    s << f.size();
    for (int k : f) s << " " << k;
    s << " 42\n";
  }
  expectReference(loadPly(plyFile("a.ply", s.str())), false);
}

struct BinaryCase {
  const char* name;
  bool bigEndian;
  bool doubles;
  const char* countType;
  const char* indexType;
};

class PlyBinary : public ::testing::TestWithParam<BinaryCase> {};

template <typename T>
void putAs(Bytes& b, const char* type, T v) {
  std::string t = type;
  if (t == "uchar" || t == "uint8")
    b.put(uint8_t(v));
  else if (t == "char" || t == "int8")
    b.put(int8_t(v));
  else if (t == "ushort" || t == "uint16")
    b.put(uint16_t(v));
  else if (t == "short" || t == "int16")
    b.put(int16_t(v));
  else if (t == "uint" || t == "uint32")
    b.put(uint32_t(v));
  else if (t == "int" || t == "int32")
    b.put(int32_t(v));
  else
    FAIL() << "type " << t;
}

TEST_P(PlyBinary, EncodesTheReferenceMesh) {
  const BinaryCase& c = GetParam();
  Bytes b;
  b.bigEndian = c.bigEndian;
  const char* real = c.doubles ? "double" : "float";
  b.s = std::string("ply\nformat ") + (c.bigEndian ? "binary_big_endian" : "binary_little_endian") +
        " 1.0\nelement vertex 6\nproperty " + real + " x\nproperty " + real +
        " y\nproperty list ushort float normals\nproperty " + real +
        " z\nelement face 3\nproperty uchar kind\nproperty list " + c.countType + " " +
        c.indexType +
        " vertex_indices\nelement material 2\nproperty float shininess\n"
        "property list uchar uchar name\nend_header\n";
  for (int i = 0; i < 6; ++i) {
    for (int a = 0; a < 2; ++a)
      c.doubles ? b.put(kReferenceVertices[3 * i + a])
                : b.put(float(kReferenceVertices[3 * i + a]));
    b.put(uint16_t(2));
    b.put(1.5f);
    b.put(-2.5f);
    c.doubles ? b.put(kReferenceVertices[3 * i + 2]) : b.put(float(kReferenceVertices[3 * i + 2]));
  }
  for (const auto& f : kReferenceFaces) {
    b.put(uint8_t(9));
    putAs(b, c.countType, f.size());
    for (int k : f) putAs(b, c.indexType, k);
  }
  for (int m = 0; m < 2; ++m) {
    b.put(0.25f);
    b.put(uint8_t(3));
    b.s += "abc";
  }
  expectReference(loadPly(plyFile("b.ply", b.s)), c.doubles);
}

INSTANTIATE_TEST_SUITE_P(
    PlyVariants, PlyBinary,
    ::testing::Values(BinaryCase{"le_float_uchar_int", false, false, "uchar", "int"},
                      BinaryCase{"be_float_uchar_int", true, false, "uchar", "int"},
                      BinaryCase{"le_double_ushort_short", false, true, "ushort", "short"},
                      BinaryCase{"be_double_int_uint", true, true, "int", "uint"},
                      BinaryCase{"le_float_uint8_int32", false, false, "uint8", "int32"},
                      BinaryCase{"be_float_char_ushort", true, false, "char", "ushort"},
                      BinaryCase{"le_double_int16_uint32", false, true, "int16", "uint32"}),
    [](const auto& p) { return std::string(p.param.name); });

// Plain layout (float xyz, uchar/int faces) goes through the loader's fast paths.
TEST(PlyBinary, FastPathLayout) {
  for (bool be : {false, true}) {
    Bytes b;
    b.bigEndian = be;
    b.s = std::string("ply\nformat ") + (be ? "binary_big_endian" : "binary_little_endian") +
          " 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
          "element face 3\nproperty list uchar int vertex_indices\nend_header\n";
    for (double v : kReferenceVertices) b.put(float(v));
    for (const auto& f : kReferenceFaces) {
      b.put(uint8_t(f.size()));
      for (int k : f) b.put(int32_t(k));
    }
    expectReference(loadPly(plyFile("f.ply", b.s)), false);
  }
}

// Strip 0 1 2 3 4 gives (0,1,2) (2,1,3) (2,3,4); -1 restarts: 5 3 1 gives (5,3,1).
TEST(PlyTristrips, RestartsAndAlternatingWinding) {
  const std::vector<uint32_t> expected = {0, 1, 2, 2, 1, 3, 2, 3, 4, 5, 3, 1};
  std::string header =
      "element vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
      "element tristrips 1\nproperty list int int vertex_indices\nend_header\n";
  std::ostringstream a;
  a << "ply\nformat ascii 1.0\n" << header;
  for (int i = 0; i < 6; ++i)
    a << kReferenceVertices[3 * i] << " " << kReferenceVertices[3 * i + 1] << " "
      << kReferenceVertices[3 * i + 2] << "\n";
  a << "9 0 1 2 3 4 -1 5 3 1\n";
  Mesh ma = loadPly(plyFile("s.ply", a.str()));
  EXPECT_EQ(test::asVector(ma.indices), expected);
  EXPECT_EQ(ma.stats.sourceFaces, 2u);

  Bytes b;
  b.s = "ply\nformat binary_little_endian 1.0\n" + header;
  for (double v : kReferenceVertices) b.put(float(v));
  b.put(int32_t(9));
  for (int v : {0, 1, 2, 3, 4, -1, 5, 3, 1}) b.put(int32_t(v));
  EXPECT_EQ(test::asVector(loadPly(plyFile("s2.ply", b.s)).indices), expected);
}

TEST(PlyAscii, VertexIndexNameAndCrlf) {
  std::string s =
      "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float32 x\r\nproperty float32 "
      "y\r\nproperty float32 z\r\nelement face 1\r\nproperty list uint8 int32 vertex_index\r\n"
      "end_header\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n";
  Mesh m = loadPly(plyFile("c.ply", s));
  EXPECT_EQ(test::asVector(m.indices), (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(test::asVector(m.positions), (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
}

}  // namespace
}  // namespace aperture
