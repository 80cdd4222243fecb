// Loading meshes (core/mesh/mesh.cpp): loadMesh's dispatch by extension and its errors (the
// tests/data/bad corpus, directories, missing files, huge counts, non-finite vertices),
// finishMesh's anchoring, padding and degenerate counts, and the shared meshes.
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

std::string tmpFile(const std::string& name, const std::string& bytes) {
  std::string path = scratchDir() + "/" + name;
  writeFile(path, bytes);
  return path;
}

std::string expectError(const std::string& spec) {
  try {
    loadMesh(spec);
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << spec << " loaded without an error";
  return "";
}

// Each file under tests/data/bad must fail in the loader with its manifest substring and
// the file's name in the message.
TEST(LoaderBadFiles, EveryCorpusFileFailsWithItsMessage) {
  const std::string dir = std::string(APERTURE_TESTS_DIR) + "/data/bad";
  std::ifstream manifest(dir + "/EXPECTED.txt");
  ASSERT_TRUE(manifest) << "missing " << dir << "/EXPECTED.txt";
  std::string line;
  int count = 0;
  while (std::getline(manifest, line)) {
    if (line.empty() || line[0] == '#') continue;
    size_t tab = line.find('\t');
    ASSERT_NE(tab, std::string::npos) << "manifest line without a tab: " << line;
    std::string file = line.substr(0, tab), expected = line.substr(tab + 1);
    ASSERT_TRUE(test::fileExists(dir + "/" + file)) << file;
    auto start = std::chrono::steady_clock::now();
    std::string msg = expectError(dir + "/" + file);
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_NE(msg.find(file), std::string::npos) << file << ": message lacks the file: " << msg;
    EXPECT_NE(msg.find(expected), std::string::npos)
        << file << ": expected '" << expected << "' in: " << msg;
    EXPECT_LT(seconds, 5.0) << file << " (a bad file must fail fast)";
    ++count;
  }
  EXPECT_GE(count, 20);
}

TEST(LoaderErrors, DirectoryMissingUnknownExtension) {
  std::string dir = scratchDir() + "/meshdir.ply";
  std::filesystem::create_directories(dir);
  std::string msg = expectError(dir);
  EXPECT_NE(msg.find("is a directory"), std::string::npos) << msg;
  EXPECT_NE(msg.find(dir), std::string::npos) << msg;

  msg = expectError(scratchDir() + "/absent.obj");
  EXPECT_NE(msg.find("absent.obj: no such file"), std::string::npos) << msg;

  msg = expectError(tmpFile("model.STL", "solid x\n"));
  EXPECT_NE(msg.find("model.STL: unknown mesh file extension '.stl'"), std::string::npos) << msg;
}

TEST(LoaderErrors, ExtensionIsCaseInsensitive) {
  Mesh m = loadMesh(tmpFile("UPPER.OBJ", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_EQ(m.triangleCount(), 1u);
}

TEST(LoaderErrors, HugeBinaryCountFailsWithoutAllocating) {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1000000000000\n"
      "property list uchar int vertex_indices\nend_header\n" +
      std::string(100, '\0');
  std::string msg = expectError(tmpFile("huge.ply", s));
  EXPECT_NE(msg.find("claims 1000000000000 items"), std::string::npos) << msg;
  EXPECT_NE(msg.find("larger than the file"), std::string::npos) << msg;
}

TEST(LoaderErrors, NonFiniteVerticesAreCountedAndTheirTrianglesDropped) {
  std::string s =
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
      "property float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\nnan 1 0\n0 1 0\n5 inf 0\n3 0 1 3\n3 0 1 2\n3 1 4 3\n";
  Mesh m = loadMesh(tmpFile("nan.ply", s));
  EXPECT_EQ(m.stats.nonFiniteVertices, 2u);
  EXPECT_EQ(m.stats.droppedTriangles, 2u);
  EXPECT_EQ(test::asVector(m.indices), (std::vector<uint32_t>{0, 1, 3}));
  // Anchor from the finite vertices only: bbox (0,0,0)-(1,1,0).
  EXPECT_EQ(m.anchor, glm::dvec3(0.5, 0.5, 0));
  EXPECT_EQ(m.vertex(2), glm::vec3(0));
  EXPECT_EQ(m.vertex(4), glm::vec3(0));
  EXPECT_EQ(m.vertex(1), glm::vec3(0.5, -0.5, 0));
}

// ---- finishMesh ----

Mesh triangleSoup() {
  Mesh m;
  m.name = "soup";
  m.positionsDouble = {1, 2, 3, 5, 2, 3, 1, 8, 3, 1, 2, 11, 3, 3, 3};
  m.vertexCount = 5;
  m.indices = {0, 1, 2, 0, 1, 3, 1, 2, 3, 4, 4, 0};
  return m;
}

TEST(FinishMesh, AnchorIsBoundingBoxCentreAndPositionsArePadded) {
  Mesh m = triangleSoup();
  finishMesh(m, {});
  EXPECT_EQ(m.anchor, glm::dvec3(3, 5, 7));
  ASSERT_EQ(m.positions.size(), 15 + kVertexPaddingFloats);
  for (size_t i = 15; i < m.positions.size(); ++i) EXPECT_EQ(m.positions[i], 0.0f);
  EXPECT_EQ(m.vertex(0), glm::vec3(-2, -3, -4));
  EXPECT_EQ(m.vertex(3), glm::vec3(-2, -3, 4));
  EXPECT_TRUE(m.positionsDouble.empty());
  EXPECT_EQ(m.stats.degenerateTriangles, 1u);
  EXPECT_EQ(m.triangleCount(), 4u);
  glm::vec3 lo, hi;
  m.bounds(lo, hi);
  EXPECT_EQ(lo, glm::vec3(-2, -3, -4));
  EXPECT_EQ(hi, glm::vec3(2, 3, 4));
}

TEST(FinishMesh, WorldSpaceAnchorIsOriginAndScaleTranslateApply) {
  Mesh m = triangleSoup();
  LoadOptions o;
  o.placement = Placement::WorldSpace;
  o.scale = 2;
  o.translate = {1, 0, -1};
  finishMesh(m, o);
  EXPECT_EQ(m.anchor, glm::dvec3(0));
  EXPECT_EQ(m.vertex(1), glm::vec3(11, 4, 5));
}

// Every way a triangle can repeat an index (first and second, second and third, first and
// third, all three), over two of finishMesh's chunks, counted against a plain loop here. A
// mesh without non-finite vertices, so the count is the index scan's.
TEST(FinishMesh, CountsEveryKindOfDegenerateTriangle) {
  Mesh m;
  m.name = "repeats";
  m.vertexCount = 1000;
  for (size_t k = 0; k < m.vertexCount; ++k)
    for (int a = 0; a < 3; ++a) m.positions.push_back(float((k * 7 + size_t(a) * 3) % 101));
  size_t degenerate = 0;
  for (uint32_t t = 0; t < 70000; ++t) {
    uint32_t v[3] = {t % 1000, (t + 1) % 1000, (t + 2) % 1000};
    if (t % 7 == 1) v[1] = v[0];
    if (t % 7 == 3) v[2] = v[1];
    if (t % 7 == 5) v[2] = v[0];
    if (t % 7 == 6) v[1] = v[2] = v[0];
    m.indices.insert(m.indices.end(), v, v + 3);
    degenerate += v[0] == v[1] || v[1] == v[2] || v[0] == v[2];
  }
  finishMesh(m, {});
  EXPECT_EQ(m.stats.degenerateTriangles, degenerate);
  EXPECT_EQ(m.triangleCount(), 70000u);  // kept: Embree skips them
}

TEST(FinishMesh, OutOfRangeIndexNamesTheMeshAndCountsBadIndices) {
  Mesh m = triangleSoup();
  m.indices = {0, 1, 7, 0, 9, 2, 1, 2, 3};
  try {
    finishMesh(m, {});
    FAIL() << "no error";
  } catch (const Error& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("soup: 2 vertex indices out of range"), std::string::npos) << msg;
    EXPECT_NE(msg.find("the first is 7 in triangle 0"), std::string::npos) << msg;
  }
}

/// Compares bit for bit what finishMesh makes of float positions `m` with `o` (no transform:
/// its plain path, box and positions without per-vertex tests) with the definition, computed
/// here vertex by vertex in order: the box of the finite world vertices
/// (scale * p + translate) by glm::min and glm::max, its centre as the anchor, and each finite
/// vertex minus the anchor rounded to float (0 for the others).
void expectFinishedAsDefined(const Mesh& m, const LoadOptions& o) {
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  std::vector<glm::dvec3> world;
  std::vector<bool> finite;
  for (size_t k = 0; k < m.vertexCount; ++k) {
    const glm::dvec3 p(m.positions[3 * k], m.positions[3 * k + 1], m.positions[3 * k + 2]);
    world.push_back(o.scale * p + o.translate);
    finite.push_back(std::isfinite(world[k].x) && std::isfinite(world[k].y) &&
                     std::isfinite(world[k].z));
    if (finite[k]) lo = glm::min(lo, world[k]), hi = glm::max(hi, world[k]);
  }
  const glm::dvec3 anchor =
      o.placement == Placement::WorldSpace ? glm::dvec3(0.0) : 0.5 * (lo + hi);
  Mesh finished = m;
  finishMesh(finished, o);
  EXPECT_EQ(std::memcmp(&finished.anchor, &anchor, sizeof(glm::dvec3)), 0)
      << "anchor " << finished.anchor.x << " " << finished.anchor.y << " " << finished.anchor.z
      << ", defined " << anchor.x << " " << anchor.y << " " << anchor.z;
  size_t differ = 0;
  for (size_t k = 0; k < m.vertexCount; ++k) {
    const glm::vec3 want = finite[k] ? glm::vec3(world[k] - anchor) : glm::vec3(0.0f);
    differ += std::memcmp(&finished.positions[3 * k], &want, sizeof(glm::vec3)) != 0;
  }
  EXPECT_EQ(differ, 0u) << "vertices whose anchored position differs";
}

// Over several of finishMesh's chunks: a flat mesh (y = 0, both signs of zero, kept by a
// translate of -0, so the order of the comparisons decides the sign of the y bounds and of
// the anchored y), scaled and moved, camera-relative and in world space, then with a
// non-finite vertex in one chunk (which that chunk's per-vertex pass leaves out). The last
// chunk's 3395 vertices end with three outside the whole blocks of four that the plain path
// places together. Taking the last of equal values instead of the first fails it.
TEST(FinishMesh, FloatPositionsWithoutTransformMatchTheGeneralPath) {
  std::mt19937 random(5);
  std::uniform_real_distribution<float> coordinate(-3.0f, 7.0f);
  Mesh m;
  m.name = "plain";
  m.vertexCount = 3 * 65536 + 3395;
  for (size_t k = 0; k < m.vertexCount; ++k) {
    m.positions.push_back(coordinate(random));
    m.positions.push_back(random() % 2 ? 0.0f : -0.0f);
    m.positions.push_back(coordinate(random));
  }
  for (size_t t = 0; t < 150000; ++t)
    for (int c = 0; c < 3; ++c) m.indices.push_back(uint32_t(random() % m.vertexCount));
  LoadOptions o;
  o.scale = 0.75;
  o.translate = {1e3, -0.0, 3.0};
  expectFinishedAsDefined(m, o);
  o.placement = Placement::WorldSpace;
  expectFinishedAsDefined(m, o);
  m.positions[3 * 140000 + 2] = std::numeric_limits<float>::infinity();
  o.placement = Placement::CameraRelative;
  expectFinishedAsDefined(m, o);
}

TEST(FinishMesh, FarFromOriginKeepsRelativePrecision) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
      "property double z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
  // Dyadic values stay exact when offset by 1e7 in double, so only the anchoring can differ.
  const double pts[4][3] = {
      {0.125, 0.5, -0.25}, {1.0625, 0.5, -0.25}, {0.375, 1.75, 0.0625}, {0.875, 0.1875, 0.625}};
  std::ostringstream near, far;
  near.precision(17);
  far.precision(17);
  near << ply;
  far << ply;
  for (const auto& p : pts) {
    near << p[0] << " " << p[1] << " " << p[2] << "\n";
    far << p[0] + 1e7 << " " << p[1] - 1e7 << " " << p[2] + 1e7 << "\n";
  }
  near << "3 0 1 2\n3 0 2 3\n";
  far << "3 0 1 2\n3 0 2 3\n";
  Mesh a = loadMesh(tmpFile("near.ply", near.str()));
  Mesh b = loadMesh(tmpFile("far.ply", far.str()));
  LoadOptions shifted;
  shifted.translate = {-1e7, 1e7, 3e7};
  Mesh c = loadMesh(tmpFile("near2.ply", near.str()), shifted);
  const double size = 1.5;
  for (size_t k = 0; k < 4; ++k)
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(b.vertex(k)[i], a.vertex(k)[i], 1e-9 * size) << k << " " << i;
      EXPECT_NEAR(c.vertex(k)[i], a.vertex(k)[i], 1e-9 * size) << k << " " << i;
    }
  EXPECT_NEAR(b.anchor.x - a.anchor.x, 1e7, 1e-6);
  EXPECT_NEAR(c.anchor.z - a.anchor.z, 3e7, 1e-6);
  // In world space, float32 cannot hold the offsets: the shapes differ.
  LoadOptions world;
  world.placement = Placement::WorldSpace;
  Mesh w = loadMesh(tmpFile("far2.ply", far.str()), world);
  EXPECT_GT(std::fabs(double(w.vertex(1).x - w.vertex(0).x) - (pts[1][0] - pts[0][0])), 1e-3);
}

// ---- Shared meshes ----

TEST(LoaderShared, BunnyPlyAndObjAgree) {
  APERTURE_REQUIRE_SHARED_MESH(plyPath, "stanford/bun_zipper.ply");
  APERTURE_REQUIRE_SHARED_MESH(objPath, "obj/stanford-bunny.obj");
  LoadOptions world;
  world.placement = Placement::WorldSpace;
  Mesh ply = loadMesh(plyPath, world);
  Mesh obj = loadMesh(objPath, world);
  ASSERT_EQ(ply.triangleCount(), 69451u);
  ASSERT_EQ(obj.triangleCount(), 69451u);
  EXPECT_EQ(ply.vertexCount, 35947u);
  EXPECT_EQ(obj.vertexCount, 35947u);
  // The OBJ keeps the PLY's vertex and face order (checked below) but prints 6 decimals
  // where the PLY has 6 significant digits: corners agree to the OBJ's rounding, 5e-7.
  size_t sameIndices = 0;
  for (size_t t = 0; t < ply.triangleCount(); ++t) {
    bool same = true;
    for (int c = 0; c < 3; ++c) {
      glm::vec3 a = ply.vertex(ply.indices[3 * t + c]), b = obj.vertex(obj.indices[3 * t + c]);
      for (int i = 0; i < 3; ++i) ASSERT_NEAR(a[i], b[i], 6e-7f) << "triangle " << t;
      same = same && ply.indices[3 * t + c] == obj.indices[3 * t + c];
    }
    sameIndices += same;
  }
  EXPECT_EQ(sameIndices, ply.triangleCount());
}

double megabytesPerSecond(const Mesh& m) {
  return double(m.stats.fileBytes) / 1e6 / m.stats.loadSeconds;
}

TEST(LoaderShared, IgeaStrips) {
  APERTURE_REQUIRE_SHARED_MESH(path, "ply/igea.ply");
  Mesh m = loadMesh(path);
  // The README's 268,686 counts every strip triangle, degenerate ones included; they are kept
  // (Embree skips them) and reported in degenerateTriangles.
  EXPECT_EQ(m.triangleCount(), 268686u);
  EXPECT_EQ(m.vertexCount, 134345u);
  std::cout << "[ info ] igea: " << m.stats.degenerateTriangles << " degenerate triangles, "
            << m.stats.sourceFaces << " strips\n";
}

TEST(LoaderShared, CrownAndDragonLoadSpeed) {
  APERTURE_REQUIRE_SHARED_MESH(crown, "scenes/crown_flat.ply");
  APERTURE_REQUIRE_SHARED_MESH(dragon, "stanford/dragon_vrip.ply");
  Mesh c = loadMesh(crown);
  EXPECT_EQ(c.triangleCount(), 3540214u);
  EXPECT_EQ(c.vertexCount, 1868139u);
  Mesh d = loadMesh(dragon);
  EXPECT_EQ(d.triangleCount(), 871414u);
  EXPECT_EQ(d.vertexCount, 437645u);
  // For information only; no timing assertions.
  std::cout << "[ info ] crown: " << c.stats.loadSeconds << " s, " << megabytesPerSecond(c)
            << " MB/s; dragon (ASCII): " << d.stats.loadSeconds << " s, " << megabytesPerSecond(d)
            << " MB/s\n";
}

TEST(LoaderShared, BathroomAndSmallObjs) {
  APERTURE_REQUIRE_SHARED_MESH(bath, "scenes/contemporary-bathroom_flat.ply");
  APERTURE_REQUIRE_SHARED_MESH(teapot, "obj/teapot.obj");
  APERTURE_REQUIRE_SHARED_MESH(spot, "obj/spot.obj");
  APERTURE_REQUIRE_SHARED_MESH(res4, "stanford/bun_zipper_res4.ply");
  EXPECT_EQ(loadMesh(bath).triangleCount(), 592188u);
  EXPECT_EQ(loadMesh(teapot).triangleCount(), 6320u);
  EXPECT_EQ(loadMesh(spot).triangleCount(), 5856u);
  EXPECT_EQ(loadMesh(res4).triangleCount(), 948u);
}

}  // namespace
}  // namespace aperture
