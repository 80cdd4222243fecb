// PLY with per-face values (core/io/ply_writer.h): the header text, the binary body parsed here
// byte by byte from the PLY format, and the project's loader reading the file back with the
// face properties (world positions exact in double, -1 as 0xFFFFFFFF).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/ply_writer.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::errorOf;

/// Two triangles far from the origin: anchor + small float offsets.
Mesh twoTriangles() {
  Mesh mesh;
  mesh.anchor = {1.0e6 + 0.5, -2.0e5 - 0.25, 3.0};
  mesh.positions = {0.0f, 0.0f, 0.0f, 1.5f, 0.0f, 0.0f, 0.0f, 2.25f, 0.0f, -0.125f, 0.5f, 1.0f};
  mesh.positions.resize(mesh.positions.size() + kVertexPaddingFloats, 0.0f);
  mesh.vertexCount = 4;
  mesh.indices = {0, 1, 2, 2, 1, 3};
  return mesh;
}

double world(const Mesh& mesh, size_t k, int a) {
  return mesh.anchor[a] + double(mesh.positions[3 * k + size_t(a)]);
}

template <typename T>
T at(const std::string& bytes, size_t offset) {
  T v;
  EXPECT_LE(offset + sizeof(T), bytes.size());
  std::memcpy(&v, bytes.data() + offset, sizeof(T));  // x86-64 is little-endian, as the file
  return v;
}

struct Written {
  Mesh mesh = twoTriangles();
  std::vector<uint32_t> viewCount = {3, 0};
  std::vector<uint32_t> bestView = {2, uint32_t(-1)};
  std::string path;

  Written() {
    path = test::scratchDir() + "/faces.ply";
    writePlyWithFaceProperties(path, mesh,
                               {{"view_count", PlyType::UInt32, viewCount.data()},
                                {"best_view", PlyType::Int32, bestView.data()}});
  }
};

const char* const kHeader =
    "ply\n"
    "format binary_little_endian 1.0\n"
    "comment aperture: vertices in world coordinates\n"
    "element vertex 4\n"
    "property double x\n"
    "property double y\n"
    "property double z\n"
    "element face 2\n"
    "property list uchar int vertex_indices\n"
    "property uint view_count\n"
    "property int best_view\n"
    "end_header\n";

TEST(PlyWriter, HeaderText) {
  const Written w;
  const std::string bytes = test::readFile(w.path);
  EXPECT_EQ(bytes.substr(0, std::strlen(kHeader)), kHeader);
}

TEST(PlyWriter, BodyParsedByHand) {
  const Written w;
  const std::string bytes = test::readFile(w.path);
  size_t p = std::strlen(kHeader);
  ASSERT_EQ(bytes.size(), p + 4 * 24 + 2 * (1 + 12 + 4 + 4));
  for (size_t k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a, p += 8)
      EXPECT_EQ(at<double>(bytes, p), world(w.mesh, k, a)) << "vertex " << k << " axis " << a;
  for (size_t t = 0; t < 2; ++t) {
    EXPECT_EQ(at<uint8_t>(bytes, p), 3);
    p += 1;
    for (int c = 0; c < 3; ++c, p += 4)
      EXPECT_EQ(at<int32_t>(bytes, p), int32_t(w.mesh.indices[3 * t + size_t(c)]));
    EXPECT_EQ(at<uint32_t>(bytes, p), w.viewCount[t]);
    EXPECT_EQ(at<int32_t>(bytes, p + 4), t == 0 ? 2 : -1);
    p += 8;
  }
}

TEST(PlyWriter, LoaderReadsItBackWithTheFaceProperties) {
  const Written w;
  LoadOptions options;
  options.properties = {{PropertyDomain::Face, "view_count"}, {PropertyDomain::Face, "best_view"}};
  // loadPly leaves double coordinates unanchored: the file's values exactly.
  const Mesh back = loadPly(w.path, options);
  ASSERT_EQ(back.vertexCount, 4u);
  ASSERT_EQ(back.positionsDouble.size(), 12u);
  for (size_t k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a)
      EXPECT_EQ(back.positionsDouble[3 * k + size_t(a)], world(w.mesh, k, a));
  EXPECT_EQ(back.indices, w.mesh.indices);
  const MeshProperty* views = back.property(PropertyDomain::Face, "view_count");
  const MeshProperty* best = back.property(PropertyDomain::Face, "best_view");
  ASSERT_TRUE(views && best);
  EXPECT_EQ(views->values, (std::vector<uint32_t>{3, 0}));
  EXPECT_EQ(best->values, (std::vector<uint32_t>{2, 0xffffffffu}));

  // Through loadMesh (anchored and in float again): the same world positions to float
  // precision of the anchored offsets.
  const Mesh finished = loadMesh(w.path, options);
  for (size_t k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(world(finished, k, a), world(w.mesh, k, a), 1e-6) << k << " " << a;
}

TEST(PlyWriter, RefusalsNameTheFileAndLeaveNone) {
  const Mesh mesh = twoTriangles();
  const std::vector<uint32_t> values = {1, 2};
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/bad.ply";
  for (const PlyFaceProperty& bad :
       {PlyFaceProperty{"view_count", PlyType::Float32, values.data()},
        PlyFaceProperty{"view count", PlyType::UInt32, values.data()},
        PlyFaceProperty{"", PlyType::UInt32, values.data()},
        PlyFaceProperty{"vertex_indices", PlyType::UInt32, values.data()},
        PlyFaceProperty{"view_count", PlyType::UInt32, nullptr}}) {
    const std::string message = errorOf([&] { writePlyWithFaceProperties(path, mesh, {bad}); });
    EXPECT_NE(message.find(path), std::string::npos) << bad.name << ": " << message;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

}  // namespace
}  // namespace aperture
