// Integer face and vertex properties (face.NAME, vertex.NAME AOVs): PLY loading (ASCII and
// binary, polygons fanned, strips, signed values, dropped triangles), the per-pixel values
// checked against the grid cell a pixel's position falls in (not against primID), the
// nearest-vertex rule against barycentric weights computed here in double, and the errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "cameras/registry/registry.h"
#include "core/engine/render.h"
#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::errorOf;

constexpr int kRows = 3, kCols = 4;

/// The id of grid cell (row r, column c): negative for the first cells, so signed storage
/// (two's complement) is exercised.
int32_t cellId(int r, int c) { return 100 * r + c - 5; }
/// Vertex label: any pattern that differs between neighbours.
uint8_t vertexLabel(size_t k) { return uint8_t((k * 7 + 3) % 23); }

/// A planar grid z = 0 of kRows x kCols unit cells, cell (r, c) = [c, c+1] x [r, r+1], made of
/// quads, triangle pairs and pentagons (an extra vertex on the bottom edge), plus a triangle
/// on a NaN vertex (dropped at load) in the middle of the face list.
struct GridPly {
  std::vector<float> xyz;  // 3 per vertex
  std::vector<std::vector<uint32_t>> faces;
  std::vector<int32_t> ids;
  std::vector<uint8_t> kinds;

  GridPly() {
    auto vertexAt = [](int r, int c) { return uint32_t(r * (kCols + 1) + c); };
    for (int r = 0; r <= kRows; ++r)
      for (int c = 0; c <= kCols; ++c) xyz.insert(xyz.end(), {float(c), float(r), 0.0f});
    for (int r = 0; r < kRows; ++r)
      for (int c = 0; c < kCols; ++c) {
        const uint32_t a = vertexAt(r, c), b = vertexAt(r, c + 1), d = vertexAt(r + 1, c + 1),
                       e = vertexAt(r + 1, c);
        const int kind = (r * kCols + c) % 3;
        if (kind == 0) {
          add({a, b, d, e}, cellId(r, c), 4);
        } else if (kind == 1) {
          add({a, b, d}, cellId(r, c), 3);
          add({a, d, e}, cellId(r, c), 3);
        } else {
          const uint32_t mid = uint32_t(xyz.size() / 3);
          xyz.insert(xyz.end(), {float(c) + 0.5f, float(r), 0.0f});
          add({a, mid, b, d, e}, cellId(r, c), 5);
        }
        if (r == 1 && c == 1) {  // the NaN vertex's triangle, between cells
          const uint32_t nan = uint32_t(xyz.size() / 3);
          xyz.insert(xyz.end(), {std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f});
          add({a, b, nan}, 999, 3);
        }
      }
  }
  void add(std::vector<uint32_t> f, int32_t id, uint8_t kind) {
    faces.push_back(std::move(f));
    ids.push_back(id);
    kinds.push_back(kind);
  }
  size_t vertexCount() const { return xyz.size() / 3; }

  std::string header(const char* format) const {
    return cat("ply\nformat ", format, " 1.0\nelement vertex ", vertexCount(),
               "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar label\n"
               "property float confidence\nelement face ",
               faces.size(),
               "\nproperty uchar kind\nproperty list uchar int vertex_indices\n"
               "property int object_id\nend_header\n");
  }
  std::string ascii() const {
    std::string s = header("ascii");
    for (size_t k = 0; k < vertexCount(); ++k) {
      const float x = xyz[3 * k];
      s += cat(std::isnan(x) ? std::string("nan") : cat(x), " ", xyz[3 * k + 1], " ",
               xyz[3 * k + 2], " ", int(vertexLabel(k)), " 0.5\n");
    }
    for (size_t f = 0; f < faces.size(); ++f) {
      s += cat(int(kinds[f]), " ", faces[f].size());
      for (uint32_t v : faces[f]) s += cat(" ", v);
      s += cat(" ", ids[f], "\n");
    }
    return s;
  }
  std::string binary() const {
    std::string s = header("binary_little_endian");
    auto put = [&](const void* p, size_t n) { s.append(static_cast<const char*>(p), n); };
    for (size_t k = 0; k < vertexCount(); ++k) {
      put(&xyz[3 * k], 12);
      const uint8_t label = vertexLabel(k);
      put(&label, 1);
      const float confidence = 0.5f;
      put(&confidence, 4);
    }
    for (size_t f = 0; f < faces.size(); ++f) {
      put(&kinds[f], 1);
      const uint8_t n = uint8_t(faces[f].size());
      put(&n, 1);
      for (uint32_t v : faces[f]) put(&v, 4);
      put(&ids[f], 4);
    }
    return s;
  }
};

LoadOptions withProperties(const std::string& list) {
  LoadOptions o;
  o.placement = Placement::WorldSpace;
  o.properties = parseAovSet(list).properties;
  return o;
}

std::string writeGrid(const std::string& bytes, const char* name) {
  const std::string path = test::scratchDir() + "/" + name;
  test::writeFile(path, bytes);
  return path;
}

class MeshPropertiesTest : public ::testing::TestWithParam<bool> {
 protected:
  std::string path() {
    const GridPly grid;
    return GetParam() ? writeGrid(grid.binary(), "grid_binary.ply")
                      : writeGrid(grid.ascii(), "grid_ascii.ply");
  }
};

TEST_P(MeshPropertiesTest, LoadsFaceValuesOnEveryTriangleAndDropsWithTheirTriangles) {
  const GridPly grid;
  const Mesh mesh = loadMesh(path(), withProperties("face.object_id,vertex.label,face.kind"));
  ASSERT_EQ(mesh.properties.size(), 3u);
  // Expected per triangle from the face list: n - 2 triangles a face, the NaN one dropped.
  std::vector<uint32_t> ids, kinds;
  for (size_t f = 0; f < grid.faces.size(); ++f) {
    if (grid.ids[f] == 999) continue;
    for (size_t t = 0; t + 2 < grid.faces[f].size(); ++t) {
      ids.push_back(uint32_t(grid.ids[f]));
      kinds.push_back(grid.kinds[f]);
    }
  }
  EXPECT_EQ(mesh.stats.droppedTriangles, 1u);
  ASSERT_EQ(mesh.triangleCount(), ids.size());
  EXPECT_EQ(mesh.property(PropertyDomain::Face, "object_id")->values, ids);
  EXPECT_EQ(mesh.property(PropertyDomain::Face, "kind")->values, kinds);
  // -5 as int32 is stored as its two's complement.
  EXPECT_EQ(mesh.property(PropertyDomain::Face, "object_id")->values.front(), 0xFFFFFFFBu);
  const MeshProperty* label = mesh.property(PropertyDomain::Vertex, "label");
  ASSERT_NE(label, nullptr);
  ASSERT_EQ(label->values.size(), grid.vertexCount());
  for (size_t k = 0; k < grid.vertexCount(); ++k) EXPECT_EQ(label->values[k], vertexLabel(k));
}

TEST_P(MeshPropertiesTest, NothingIsStoredUnasked) {
  const Mesh mesh = loadMesh(path(), LoadOptions{});
  EXPECT_TRUE(mesh.properties.empty());
  EXPECT_TRUE(mesh.vertexNormals.empty());
}

TEST_P(MeshPropertiesTest, MissingOrFloatPropertyIsAnErrorNamingFileAndProperties) {
  const std::string file = path();
  const std::string missing = errorOf([&] { loadMesh(file, withProperties("face.object_idd")); });
  EXPECT_NE(missing.find(file), std::string::npos) << missing;
  EXPECT_NE(missing.find("'object_idd'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("did you mean 'object_id'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("kind, object_id"), std::string::npos) << missing;
  const std::string isFloat = errorOf([&] { loadMesh(file, withProperties("vertex.confidence")); });
  EXPECT_NE(isFloat.find("'confidence'"), std::string::npos) << isFloat;
  EXPECT_NE(isFloat.find("float"), std::string::npos) << isFloat;
  EXPECT_NE(isFloat.find("label"), std::string::npos) << isFloat;
}

/// Barycentric weights of p in triangle (a, b, c), double.
glm::dvec3 barycentric(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                       const glm::dvec3& c) {
  const glm::dvec3 n = glm::cross(b - a, c - a);
  const double area = glm::dot(n, n);
  const double wb = glm::dot(glm::cross(p - a, c - a), n) / area;
  const double wc = glm::dot(glm::cross(b - a, p - a), n) / area;
  return {1.0 - wb - wc, wb, wc};
}

TEST_P(MeshPropertiesTest, EveryPixelShowsTheIdOfItsCellAndTheLabelOfItsNearestVertex) {
  const Mesh mesh = loadMesh(path(), withProperties("face.object_id,vertex.label"));
  const Device device;
  const Scene scene(device, std::vector<const Mesh*>{&mesh});
  // A perspective view at an angle, so cells are not aligned with pixels.
  CameraParams p;
  p.eye = {1.3, -1.0, 4.0};
  p.at = {2.0, 1.5, 0.0};
  p.width = 96;
  p.height = 72;
  p.fovDeg = 70;
  const auto camera = makeCamera(p, scene.renderOrigin());
  AovSet aovs = parseAovSet("position,primid,face.object_id,vertex.label");
  Framebuffer fb(p.width, p.height, aovs);
  RenderSettings rs;
  rs.packetWidth = 8;
  renderImage(scene, *camera, rs, fb);
  const std::vector<uint32_t>& ids = fb.properties[0].values;
  const std::vector<uint32_t>& labels = fb.properties[1].values;
  int checkedIds = 0, checkedLabels = 0, misses = 0, wrongOrder = 0;
  for (size_t px = 0; px < fb.pixelCount(); ++px) {
    if (fb.primId[px] == kInvalidId) {
      EXPECT_EQ(ids[px], kInvalidId);
      EXPECT_EQ(labels[px], kInvalidId);
      ++misses;
      continue;
    }
    const glm::dvec3 pos(fb.position[3 * px], fb.position[3 * px + 1], fb.position[3 * px + 2]);
    // Face id from the cell the hit point lies in (away from the cell borders).
    const double fx = pos.x - std::floor(pos.x), fy = pos.y - std::floor(pos.y);
    if (fx > 1e-3 && fx < 1 - 1e-3 && fy > 1e-3 && fy < 1 - 1e-3) {
      EXPECT_EQ(ids[px], uint32_t(cellId(int(std::floor(pos.y)), int(std::floor(pos.x)))))
          << "pixel " << px << " at " << pos.x << "," << pos.y;
      ++checkedIds;
    }
    // Vertex label: the triangle's corner with the largest weight, away from ties.
    const uint32_t* corner = &mesh.indices[3 * size_t(fb.primId[px])];
    glm::dvec3 v[3];
    for (int c = 0; c < 3; ++c) v[c] = glm::dvec3(mesh.vertex(corner[c])) + mesh.anchor;
    const glm::dvec3 w = barycentric(pos, v[0], v[1], v[2]);
    int best = 0;
    for (int c = 1; c < 3; ++c)
      if (w[c] > w[best]) best = c;
    double second = -1;
    for (int c = 0; c < 3; ++c)
      if (c != best) second = std::max(second, w[c]);
    if (w[best] - second < 1e-3) continue;
    EXPECT_EQ(labels[px], vertexLabel(corner[best])) << "pixel " << px;
    // The rule with the corners taken in the wrong order (u for v0...) would disagree.
    wrongOrder += labels[px] != vertexLabel(corner[(best + 1) % 3]);
    ++checkedLabels;
  }
  EXPECT_GT(checkedIds, 1000);
  EXPECT_GT(checkedLabels, 1000);
  EXPECT_GT(misses, 100);
  EXPECT_GT(wrongOrder, checkedLabels / 2);
}

INSTANTIATE_TEST_SUITE_P(AsciiAndBinary, MeshPropertiesTest, ::testing::Bool(),
                         [](const auto& param) { return param.param ? "Binary" : "Ascii"; });

TEST(MeshPropertiesStrips, EachStripsTrianglesCarryItsValue) {
  // Two strips: 5 indices (3 triangles) with id 7, then 4 with a restart (-1) inside: 1 + 0.
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
      "property float z\nelement tristrips 2\nproperty list int int vertex_indices\n"
      "property short part\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 2 0\n1 2 0\n"
      "5 0 1 2 3 4 7\n5 2 3 4 -1 5 -2\n";
  LoadOptions o = withProperties("face.part");
  Mesh mesh = loadPlyFromMemory(ply.data(), ply.size(), "strips.ply", o);
  finishMesh(mesh, o);
  ASSERT_EQ(mesh.triangleCount(), 4u);
  EXPECT_EQ(mesh.properties[0].values, (std::vector<uint32_t>{7, 7, 7, 0xFFFFFFFEu}));
}

TEST(MeshPropertiesErrors, ObjAndProceduralMeshesHaveNoProperties) {
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const std::string objError = errorOf(
      [&] { loadObjFromMemory(obj.data(), obj.size(), "t.obj", withProperties("face.id")); });
  EXPECT_NE(objError.find("face.id"), std::string::npos) << objError;
  const std::string procError =
      errorOf([&] { loadMesh("procedural:sphere", withProperties("vertex.label")); });
  EXPECT_NE(procError.find("procedural:sphere"), std::string::npos) << procError;
}

TEST(MeshPropertiesErrors, AMeshWithoutThePropertyIsRefusedBeforeRendering) {
  const Mesh sphere = loadMesh("procedural:sphere");
  const Device device;
  const Scene scene(device, std::vector<const Mesh*>{&sphere});
  CameraParams p;
  p.eye = {0, 0, 5};
  p.at = {0, 0, 0};
  p.width = 8;
  p.height = 8;
  const auto camera = makeCamera(p, scene.renderOrigin());
  Framebuffer fb(8, 8, parseAovSet("face.object_id"));
  const std::string message = errorOf([&] { renderImage(scene, *camera, RenderSettings{}, fb); });
  EXPECT_NE(message.find("procedural:sphere"), std::string::npos) << message;
  EXPECT_NE(message.find("face.object_id"), std::string::npos) << message;
}

}  // namespace
}  // namespace aperture
