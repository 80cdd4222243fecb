// The parallel binary PLY readers against the serial ones (PlyParsing::Serial): the same mesh,
// bit for bit, or the same error message, on the shared meshes, on generated files large
// enough to span many parallel tasks (float and double vertices, kept properties and normals,
// triangles, quads, mixed polygons, bad indices, truncation) and on the fuzz corpus with
// truncated and corrupted variants. Generated files are also checked against the values
// written, so a fault common to both readers fails too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/ply.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// A loaded mesh, or the message of the Error the loader threw.
struct Outcome {
  bool ok = false;
  std::string error;
  Mesh mesh;
};

Outcome load(const std::string& bytes, const std::string& name, const LoadOptions& options,
             PlyParsing parsing) {
  Outcome out;
  try {
    out.mesh = loadPlyFromMemory(bytes.data(), bytes.size(), name, options, parsing);
    out.ok = true;
  } catch (const Error& e) {
    out.error = e.what();
  }
  return out;
}

template <class T, class Allocator>
bool sameBits(const std::vector<T, Allocator>& a, const std::vector<T, Allocator>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void expectSameMesh(const Mesh& a, const Mesh& b, const std::string& what) {
  EXPECT_EQ(a.vertexCount, b.vertexCount) << what;
  EXPECT_TRUE(sameBits(a.positions, b.positions)) << what << ": positions differ";
  EXPECT_TRUE(sameBits(a.positionsDouble, b.positionsDouble))
      << what << ": double positions differ";
  EXPECT_TRUE(sameBits(a.indices, b.indices)) << what << ": indices differ";
  EXPECT_TRUE(sameBits(a.vertexNormals, b.vertexNormals)) << what << ": normals differ";
  ASSERT_EQ(a.properties.size(), b.properties.size()) << what;
  for (size_t k = 0; k < a.properties.size(); ++k)
    EXPECT_TRUE(sameBits(a.properties[k].values, b.properties[k].values))
        << what << ": property " << a.properties[k].name << " differs";
  EXPECT_EQ(a.stats.sourceFaces, b.stats.sourceFaces) << what;
  EXPECT_EQ(a.stats.nonFiniteVertices, b.stats.nonFiniteVertices) << what;
  EXPECT_EQ(a.stats.droppedTriangles, b.stats.droppedTriangles) << what;
  EXPECT_EQ(a.stats.degenerateTriangles, b.stats.degenerateTriangles) << what;
  EXPECT_TRUE(std::memcmp(&a.anchor, &b.anchor, sizeof a.anchor) == 0)
      << what << ": anchors differ";
}

/// Loads `bytes` with both readers and expects the same mesh (also after finishMesh) or the
/// same error; returns the parallel outcome.
Outcome expectSameOutcome(const std::string& bytes, const std::string& name,
                          const LoadOptions& options = {}) {
  Outcome serial = load(bytes, name, options, PlyParsing::Serial);
  Outcome parallel = load(bytes, name, options, PlyParsing::Parallel);
  EXPECT_EQ(serial.ok, parallel.ok)
      << name << ": serial '" << serial.error << "', parallel '" << parallel.error << "'";
  EXPECT_EQ(serial.error, parallel.error) << name;
  if (serial.ok && parallel.ok) {
    expectSameMesh(serial.mesh, parallel.mesh, name + " (loaded)");
    Mesh s = serial.mesh, p = parallel.mesh;
    std::string sError, pError;
    try {
      finishMesh(s, options);
    } catch (const Error& e) {
      sError = e.what();
    }
    try {
      finishMesh(p, options);
    } catch (const Error& e) {
      pError = e.what();
    }
    EXPECT_EQ(sError, pError) << name;
    if (sError.empty()) expectSameMesh(s, p, name + " (finished)");
  }
  return parallel;
}

/// Options asking for everything the readers can keep beyond positions and indices.
LoadOptions withData() {
  LoadOptions o;
  o.vertexNormals = true;
  o.properties = {{PropertyDomain::Face, "object_id"}, {PropertyDomain::Vertex, "label"}};
  return o;
}

/// A binary PLY written value by value, in little- or big-endian order.
class PlyWriter {
 public:
  explicit PlyWriter(bool bigEndian) : bigEndian_(bigEndian) {}
  template <class T>
  void put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (bigEndian_)
      for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    data_.append(b, sizeof(T));
  }
  std::string file(const std::string& elements) const {
    return std::string("ply\nformat ") +
           (bigEndian_ ? "binary_big_endian" : "binary_little_endian") + " 1.0\n" + elements +
           "end_header\n" + data_;
  }

 private:
  bool bigEndian_;
  std::string data_;
};

/// Coordinate i of a generated mesh: varied values, with a NaN (signalling, so a conversion
/// through double would change its bits), an infinity and a negative zero now and then.
float coordinate(size_t i) {
  if (i % 99991 == 17) {
    uint32_t bits = 0x7f800001u;
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
  }
  if (i % 77773 == 5) return std::numeric_limits<float>::infinity();
  if (i % 1013 == 3) return -0.0f;
  return float(std::sin(double(i) * 0.37) * 1000.0 + double(i % 7));
}

constexpr size_t kVertices = 300000;  // several of the readers' 65536-item tasks
constexpr size_t kFaces = 400000;

uint32_t corner(size_t face, size_t k) { return uint32_t((face * 7 + k * 13) % kVertices); }

TEST(PlyParallel, FloatTrianglesMatchSerialAndTheValuesWritten) {
  PlyWriter w(false);
  for (size_t i = 0; i < 3 * kVertices; ++i) w.put(coordinate(i));
  for (size_t f = 0; f < kFaces; ++f) {
    w.put(uint8_t(3));
    for (size_t k = 0; k < 3; ++k) w.put(int32_t(corner(f, k)));
  }
  const std::string file =
      w.file("element vertex " + std::to_string(kVertices) +
             "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
             std::to_string(kFaces) + "\nproperty list uchar int vertex_indices\n");
  const Outcome out = expectSameOutcome(file, "tris.ply");
  ASSERT_TRUE(out.ok) << out.error;
  ASSERT_EQ(out.mesh.positions.size(), 3 * kVertices);
  for (size_t i = 0; i < 3 * kVertices; ++i) {
    const float want = coordinate(i);
    ASSERT_EQ(std::memcmp(&out.mesh.positions[i], &want, 4), 0) << "coordinate " << i;
  }
  ASSERT_EQ(out.mesh.indices.size(), 3 * kFaces);
  for (size_t f = 0; f < kFaces; ++f)
    for (size_t k = 0; k < 3; ++k) ASSERT_EQ(out.mesh.indices[3 * f + k], corner(f, k));
  EXPECT_EQ(out.mesh.stats.sourceFaces, kFaces);
  // The parallel reader leaves room for Embree's padding, so finishMesh pads without a copy.
  EXPECT_GE(out.mesh.positions.capacity(), 3 * kVertices + kVertexPaddingFloats);
}

TEST(PlyParallel, DoubleVerticesWithDataAndQuadsMatchSerial) {
  PlyWriter w(false);
  for (size_t i = 0; i < kVertices; ++i) {
    for (int a = 0; a < 3; ++a) w.put(double(coordinate(3 * i + size_t(a))) + 1e-9 * double(i));
    w.put(uint8_t(i % 251));  // label
    for (int a = 0; a < 3; ++a) w.put(float(a) - coordinate(i));
  }
  for (size_t f = 0; f < kFaces; ++f) {
    w.put(uint8_t(4));
    for (size_t k = 0; k < 4; ++k) w.put(uint32_t(corner(f, k)));
  }
  const std::string file =
      w.file("element vertex " + std::to_string(kVertices) +
             "\nproperty double x\nproperty double y\nproperty double z\nproperty uchar label\n"
             "property float nx\nproperty float ny\nproperty float nz\nelement face " +
             std::to_string(kFaces) + "\nproperty list uchar uint vertex_indices\n");
  LoadOptions labelAndNormals;
  labelAndNormals.vertexNormals = true;
  labelAndNormals.properties = {{PropertyDomain::Vertex, "label"}};
  for (const LoadOptions& o : {LoadOptions{}, labelAndNormals}) {
    const Outcome out = expectSameOutcome(file, "quads.ply", o);
    ASSERT_TRUE(out.ok) << out.error;
    ASSERT_EQ(out.mesh.positionsDouble.size(), 3 * kVertices);
    for (size_t i = 0; i < kVertices; ++i)
      for (int a = 0; a < 3; ++a) {
        const double want = double(coordinate(3 * i + size_t(a))) + 1e-9 * double(i);
        const double got = out.mesh.positionsDouble[3 * i + size_t(a)];
        ASSERT_TRUE(got == want || (std::isnan(got) && std::isnan(want))) << i;
      }
    ASSERT_EQ(out.mesh.indices.size(), 6 * kFaces);
    for (size_t f = 0; f < kFaces; f += 997) {
      const uint32_t* t = &out.mesh.indices[6 * f];
      EXPECT_EQ(t[0], corner(f, 0));
      EXPECT_EQ(t[2], corner(f, 2));
      EXPECT_EQ(t[5], corner(f, 3));
    }
    if (!o.properties.empty()) {
      ASSERT_EQ(out.mesh.properties[0].values.size(), kVertices);
      for (size_t i = 0; i < kVertices; i += 101)
        EXPECT_EQ(out.mesh.properties[0].values[i], i % 251);
      ASSERT_EQ(out.mesh.vertexNormals.size(), 3 * kVertices);
      EXPECT_EQ(out.mesh.vertexNormals[3 * 1000 + 2], 2.0f - coordinate(1000));
    }
  }
}

/// A little- or big-endian file with mixed vertex types, an extra int property and faces of
/// `countOf(f)` corners (`badAt`: a face whose first index is -1).
std::string mixedFile(bool bigEndian, size_t (*countOf)(size_t), size_t badAt) {
  PlyWriter w(bigEndian);
  for (size_t i = 0; i < kVertices; ++i) {
    w.put(coordinate(3 * i));
    w.put(int32_t(i));
    w.put(double(coordinate(3 * i + 1)));
    w.put(coordinate(3 * i + 2));
  }
  for (size_t f = 0; f < kFaces; ++f) {
    const size_t n = countOf(f);
    w.put(uint8_t(n));
    for (size_t k = 0; k < n; ++k)
      w.put(f == badAt && k == 0 ? int32_t(-1) : int32_t(corner(f, k)));
  }
  return w.file("element vertex " + std::to_string(kVertices) +
                "\nproperty float x\nproperty int id\nproperty double y\nproperty float z\n"
                "element face " +
                std::to_string(kFaces) + "\nproperty list uchar int vertex_indices\n");
}

size_t mixedPolygons(size_t f) { return 3 + f % 3; }
size_t trianglesThenAQuad(size_t f) { return f + 1 == kFaces ? 4 : 3; }
size_t triangles(size_t) { return 3; }
/// A quad, then a face of two corners (17 + 9 bytes: as long as two triangles), midway through
/// one of the parallel reader's tasks; triangles elsewhere.
size_t aQuadThenTwoCornersMidway(size_t f) { return f == 70000 ? 4 : f == 70001 ? 2 : 3; }

TEST(PlyParallel, MixedPolygonsAndBigEndianMatchSerial) {
  for (bool bigEndian : {false, true}) {
    const std::string name = bigEndian ? "mixed_be.ply" : "mixed_le.ply";
    const Outcome out = expectSameOutcome(mixedFile(bigEndian, mixedPolygons, kFaces), name);
    ASSERT_TRUE(out.ok) << out.error;
    size_t fanTriangles = 0;
    for (size_t f = 0; f < kFaces; ++f) fanTriangles += mixedPolygons(f) - 2;
    EXPECT_EQ(out.mesh.indices.size(), 3 * fanTriangles);
    EXPECT_EQ(out.mesh.positionsDouble[3 * 12345 + 1], double(coordinate(3 * 12345 + 1)));
    EXPECT_EQ(out.mesh.positionsDouble[3 * 12345 + 2], double(coordinate(3 * 12345 + 2)));
  }
  // Every face a triangle but the last: the parallel reader must give up and leave no trace.
  const Outcome last = expectSameOutcome(mixedFile(false, trianglesThenAQuad, kFaces), "last.ply");
  ASSERT_TRUE(last.ok) << last.error;
  EXPECT_EQ(last.mesh.indices.size(), 3 * (kFaces - 1) + 6);
  EXPECT_EQ(last.mesh.stats.sourceFaces, kFaces);
  // The faces after the pair sit where the triangles' would, so only their counts tell the
  // parallel reader to give up.
  const Outcome pair =
      expectSameOutcome(mixedFile(false, aQuadThenTwoCornersMidway, kFaces), "pair.ply");
  ASSERT_TRUE(pair.ok) << pair.error;
  EXPECT_EQ(pair.mesh.indices.size(), 3 * (kFaces - 2) + 6);
}

TEST(PlyParallel, BadIndicesAndTruncationGiveTheSerialErrors) {
  for (size_t badAt : {size_t(0), size_t(70000), kFaces - 1}) {
    const Outcome out = expectSameOutcome(mixedFile(false, triangles, badAt), "bad.ply");
    EXPECT_FALSE(out.ok);
    EXPECT_NE(out.error.find("negative vertex index -1"), std::string::npos) << out.error;
    EXPECT_NE(out.error.find("face " + std::to_string(badAt) + ")"), std::string::npos)
        << out.error;
  }
  const std::string whole = mixedFile(false, triangles, kFaces);
  for (size_t cut : {size_t(1), size_t(7), size_t(13 * 1000 + 5)}) {
    const Outcome out = expectSameOutcome(whole.substr(0, whole.size() - cut), "cut.ply");
    EXPECT_FALSE(out.ok);
    EXPECT_NE(out.error.find("truncated data"), std::string::npos) << out.error;
  }
}

// finishMesh's parallel passes combine their chunks in order: the first bad index, the counts
// and the bounds are those of one pass in file order (computed here by plain loops).
TEST(PlyParallel, FinishMeshPassesAgreeWithPlainLoops) {
  Mesh mesh;
  mesh.vertexCount = kVertices;
  for (size_t i = 0; i < 3 * kVertices; ++i) mesh.positions.push_back(coordinate(i));
  for (size_t f = 0; f < kFaces; ++f)
    for (size_t k = 0; k < 3; ++k)
      mesh.indices.push_back(f % 5 == 0 && k == 2 ? corner(f, 0) : corner(f, k));
  Mesh bad = mesh;
  bad.indices[3 * 70001 + 1] = uint32_t(kVertices + 5);
  bad.indices[3 * 390000] = uint32_t(kVertices);
  try {
    finishMesh(bad, {});
    ADD_FAILURE() << "out-of-range indices were accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("2 vertex indices out of range (the mesh has 300000 "
                                         "vertices); the first is 300005 in triangle 70001"),
              std::string::npos)
        << e.what();
  }

  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  std::vector<bool> nonFinite(kVertices, false);
  size_t nonFiniteCount = 0;
  for (size_t i = 0; i < kVertices; ++i) {
    const glm::dvec3 v(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
    if (std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    } else {
      nonFinite[i] = true;
      ++nonFiniteCount;
    }
  }
  size_t dropped = 0, degenerate = 0;
  for (size_t f = 0; f < kFaces; ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    if (nonFinite[t[0]] || nonFinite[t[1]] || nonFinite[t[2]])
      ++dropped;
    else if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      ++degenerate;
  }
  ASSERT_GT(nonFiniteCount, 0u);
  ASSERT_GT(degenerate, 0u);
  finishMesh(mesh, {});
  EXPECT_EQ(mesh.stats.nonFiniteVertices, nonFiniteCount);
  EXPECT_EQ(mesh.stats.droppedTriangles, dropped);
  EXPECT_EQ(mesh.stats.degenerateTriangles, degenerate);
  const glm::dvec3 anchor = 0.5 * (lo + hi);
  EXPECT_TRUE(std::memcmp(&mesh.anchor, &anchor, sizeof anchor) == 0);
  for (size_t i = 0; i < kVertices; i += 1009) {
    const float want = nonFinite[i] ? 0.0f : float(double(coordinate(3 * i)) - anchor.x);
    EXPECT_EQ(mesh.positions[3 * i], want) << "vertex " << i;
  }
}

std::vector<std::string> filesUnder(const std::string& dir) {
  std::vector<std::string> files;
  if (!std::filesystem::is_directory(dir)) return files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
    if (entry.is_regular_file()) files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(PlyParallel, FuzzCorpusAndItsVariantsMatchSerial) {
  std::vector<std::string> files = filesUnder(std::string(APERTURE_TESTS_DIR) + "/fuzz/corpus/ply");
  for (const std::string& f : filesUnder(std::string(APERTURE_TESTS_DIR) + "/fuzz/regressions/ply"))
    files.push_back(f);
  ASSERT_FALSE(files.empty()) << "no PLY fuzz corpus under " << APERTURE_TESTS_DIR;
  for (const std::string& path : files) {
    const std::string bytes = test::readFile(path);
    ASSERT_FALSE(bytes.empty()) << path;
    for (const LoadOptions& o : {LoadOptions{}, withData()}) {
      expectSameOutcome(bytes, path, o);
      // Every truncation near the end and a sample of the others, and single corrupted bytes.
      for (size_t cut = 1; cut < bytes.size(); cut += cut < 64 ? 1 : bytes.size() / 32)
        expectSameOutcome(bytes.substr(0, bytes.size() - cut), path + " cut", o);
      for (size_t at = 0; at < bytes.size(); at += 1 + bytes.size() / 97)
        for (char value : {'\0', '\x03', '\xff'}) {
          std::string changed = bytes;
          changed[at] = value;
          expectSameOutcome(changed, path + " byte " + std::to_string(at), o);
        }
    }
  }
}

TEST(PlyParallel, SharedBinaryMeshesMatchSerial) {
  const std::string root = test::sharedDir() + "/meshes";
  if (!std::filesystem::is_directory(root))
    GTEST_SKIP() << root << " is absent: the shared meshes are not compared";
  size_t binary = 0;
  for (const std::string& path : filesUnder(root)) {
    if (lowerExtension(path) != ".ply") continue;
    const std::string bytes = test::readFile(path);
    if (bytes.find("format binary_", 0) > 200) continue;  // ASCII: no parallel reader
    ++binary;
    const Outcome out = expectSameOutcome(bytes, path);
    EXPECT_TRUE(out.ok) << out.error;
  }
  EXPECT_GE(binary, 3u) << "expected igea, the crown and the bathroom under " << root;
}

}  // namespace
}  // namespace aperture
