// The OBJ loader (core/mesh/obj.cpp): every corner form, negative indices, polygons fanned,
// statements it ignores, and faces before the vertices they use.
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// A file NAME of `text` in the test's scratch directory.
std::string objFile(const std::string& name, const std::string& text) {
  const std::string path = test::scratchDir() + "/" + name;
  test::writeFile(path, text);
  return path;
}

TEST(ObjLoader, CornerFormsNegativeIndicesPolygonsIgnoredStatements) {
  const std::string obj =
      "# comment\nmtllib x.mtl\no thing\ng group\ns 1\nusemtl red\n"
      "v 0 0 0\nv 1 0 0 1.0\nv 1 1 0\nv 0 1 0   # trailing comment\n"
      "vt 0 0\nvt 1 0\nvn 0 0 1\nvp 0.5\n"
      "f 1 2 3\n"
      "f 1/1 3/2 4/1\n"
      "f 1//1 2//1 3//1 4//1\n"
      "v 0.5 2 -1.25\nv -3 4.5 7\n"
      "f -6/1/1 -5/2/1 -2/1/1 -1/1/1 -3/2/1\n"
      "l 1 2\np 3\n\tf\t1 2 3\r\n";
  Mesh m = loadObj(objFile("t.obj", obj));
  ASSERT_EQ(m.vertexCount, 6u);
  EXPECT_EQ(m.positionsDouble,
            (std::vector<double>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 2, -1.25, -3, 4.5, 7}));
  const std::vector<uint32_t> expected = {0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3,
                                          0, 1, 4, 0, 4, 5, 0, 5, 3, 0, 1, 2};
  EXPECT_EQ(test::asVector(m.indices), expected);
  EXPECT_EQ(m.stats.sourceFaces, 5u);
}

TEST(ObjLoader, ForwardReferenceIsAllowed) {
  Mesh m = loadObj(objFile("fw.obj", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"));
  EXPECT_EQ(test::asVector(m.indices), (std::vector<uint32_t>{0, 1, 2}));
}

}  // namespace
}  // namespace aperture
