// The mesh data AOVs from the command line and job files: `render --aov face.NAME` writes a
// UINT channel of that name (0xFFFFFFFF for misses), the EXR records the normal frame, and
// a batch with "id_counts" reports per image pixel counts that sum to the hit pixels.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "core/exr/exr.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

/// Two quads side by side in z = 0 (x in [-1, 0] id 4, x in [0, 1] id 9), ASCII PLY.
std::string twoQuads() {
  return "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
         "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
         "property ushort object_id\nend_header\n"
         "-1 -1 0\n0 -1 0\n1 -1 0\n-1 1 0\n0 1 0\n1 1 0\n"
         "4 0 1 4 3 4\n4 1 2 5 4 9\n";
}

TEST(MeshAovsCli, RenderWritesThePropertyAsAUintChannel) {
  const std::string dir = test::scratchDir();
  const std::string mesh = dir + "/quads.ply", out = dir + "/ids.exr";
  test::writeFile(mesh, twoQuads());
  std::string log;
  ASSERT_EQ(
      test::runCommand(test::apertureBinary() + " render --quiet --mesh " + test::quote(mesh) +
                           " --eye 0,0,3 --at 0,0,0 --size 40,20 --fov 60 --aov "
                           "face.object_id,position,normal --normal-frame opencv --out " +
                           test::quote(out),
                       &log),
      0)
      << log;
  ExrMetadata meta;
  const Framebuffer fb = readExr(out, &meta);
  ASSERT_EQ(fb.properties.size(), 1u);
  EXPECT_EQ(fb.properties[0].property.aovName(), "face.object_id");
  const ExrHeader header = readExrHeader(out);
  EXPECT_NE(std::find(header.channels.begin(), header.channels.end(), "face.object_id"),
            header.channels.end());
  int left = 0, right = 0, misses = 0;
  for (size_t px = 0; px < fb.pixelCount(); ++px) {
    const uint32_t id = fb.properties[0].values[px];
    const double x = fb.position[3 * px];
    if (fb.normal[3 * px + 2] == 0.0f) {  // a miss: no normal
      EXPECT_EQ(id, kInvalidId);
      ++misses;
    } else if (x < -1e-4) {
      EXPECT_EQ(id, 4u) << px;
      ++left;
    } else if (x > 1e-4) {
      EXPECT_EQ(id, 9u) << px;
      ++right;
    }
  }
  EXPECT_GT(left, 50);
  EXPECT_GT(right, 50);
  EXPECT_GT(misses, 50);
  bool recorded = false;
  for (const auto& [name, value] : meta.strings)
    recorded = recorded || (name == "aperture.normalFrame" && value == "opencv");
  EXPECT_TRUE(recorded);
}

TEST(MeshAovsCli, BatchIdCountsSumToTheHitPixels) {
  const std::string dir = test::scratchDir();
  const std::string mesh = dir + "/quads.ply";
  test::writeFile(mesh, twoQuads());
  const nlohmann::json job = {
      {"scene", {{"meshes", {{{"path", mesh}}}}}},
      {"cameras",
       {{{"name", "a"}, {"eye", {0.3, 0.2, 3}}, {"at", {0, 0, 0}}, {"fov", 60}},
        {{"name", "b"}, {"eye", {-0.8, 0, 2}}, {"at", {-0.5, 0, 0}}, {"fov", 50}}}},
      {"size", {36, 24}},
      {"aovs", "geomid,face.object_id"},
      {"id_counts", true},
      {"normal_frame", "opengl"},
      {"output", dir + "/out/{camera}.exr"}};
  const std::string jobPath = dir + "/job.json";
  test::writeFile(jobPath, job.dump());
  std::string log;
  ASSERT_EQ(
      test::runCommand(test::apertureBinary() + " batch --quiet " + test::quote(jobPath), &log), 0)
      << log;
  const nlohmann::json summary = nlohmann::json::parse(test::readFile(dir + "/out/summary.json"));
  ASSERT_EQ(summary["images"].size(), 2u);
  for (const nlohmann::json& image : summary["images"]) {
    const Framebuffer fb = readExr(image["output"].get<std::string>());
    uint64_t hits = 0;
    std::map<uint32_t, uint64_t> byId;
    for (size_t px = 0; px < fb.pixelCount(); ++px)
      if (fb.geomId[px] != kInvalidId) {
        ++hits;
        ++byId[fb.properties[0].values[px]];
      }
    ASSERT_GT(hits, 0u);
    const nlohmann::json& counts = image["id_counts"];
    for (const char* aov : {"geomid", "face.object_id"}) {
      uint64_t sum = 0;
      for (const auto& [id, n] : counts[aov].items()) sum += n.get<uint64_t>();
      EXPECT_EQ(sum, hits) << aov;
    }
    for (const auto& [id, n] : byId)
      EXPECT_EQ(counts["face.object_id"][std::to_string(id)].get<uint64_t>(), n) << id;
  }
}

TEST(MeshAovsCli, UnknownNormalFrameInAJobNamesTheKey) {
  const std::string dir = test::scratchDir();
  const nlohmann::json job = {{"scene", {{"meshes", {{{"path", "procedural:sphere"}}}}}},
                              {"cameras", {{{"name", "a"}, {"eye", {0, 0, 3}}, {"at", {0, 0, 0}}}}},
                              {"size", {8, 8}},
                              {"aovs", "normal"},
                              {"normal_frame", "opencvv"},
                              {"output", dir + "/{camera}.exr"}};
  test::writeFile(dir + "/job.json", job.dump());
  std::string log;
  EXPECT_NE(test::runCommand(
                test::apertureBinary() + " batch --quiet " + test::quote(dir + "/job.json"), &log),
            0);
  EXPECT_NE(log.find("normal_frame"), std::string::npos) << log;
  EXPECT_NE(log.find("did you mean 'opencv'"), std::string::npos) << log;
}

}  // namespace
}  // namespace aperture
