// The AOV table (core/aov/aov_table.h): the docs hold its table, and a row registered by a test —
// the row and the test's own computation, no other code — is allocated, parsed, listed,
// written and read back by the EXR writer and reader, and written as a dataset file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "apps/services/limits.h"
#include "core/aov/aov_table.h"
#include "core/aov/framebuffer.h"
#include "core/exr/exr.h"
#include "core/exr/exr_header.h"
#include "core/io/dataset_image.h"
#include "core/util/error.h"
#include "tests/support.h"

using namespace aperture;

namespace {

/// The rows of the Aov enum (core/aov/framebuffer.h): color .. albedo.
constexpr size_t kFixedAovRows = 15;

TEST(AovTable, DocsHoldTheGeneratedTable) {
  const std::string table = aovMarkdownTable();
  for (const char* file : {"/../docs/aovs.md", "/../README.md"}) {
    const std::string docs = test::readFile(std::string(APERTURE_TESTS_DIR) + file);
    EXPECT_NE(docs.find(table), std::string::npos)
        << file << " does not hold the AOV table of core/aov/aov_table.cpp; paste this one:\n"
        << table;
  }
}

TEST(AovTable, FixedRowsAreTheEnumBitsInOrder) {
  const std::vector<AovRow>& rows = aovTable();
  ASSERT_GE(rows.size(), kFixedAovRows);
  AovMask seen = 0;
  for (size_t k = 0; k < kFixedAovRows; ++k) {
    EXPECT_EQ(rows[k].bit, AovMask(1u << k)) << rows[k].name;
    EXPECT_TRUE(rows[k].f32 || rows[k].u32) << rows[k].name << " has no framebuffer member";
    EXPECT_EQ(rows[k].f32 != nullptr, rows[k].isFloat()) << rows[k].name;
    seen |= rows[k].bit;
  }
  EXPECT_EQ(seen, AovMask((1u << kFixedAovRows) - 1));
  EXPECT_EQ(rows[kFixedAovRows - 1].bit, AovMask(kAovAlbedo)) << "the last enum bit";
}

// The layered hits are the columns of the four rows the layer tracer fills, as docs/layers.md
// names them: hit<k>.Z hit<k>.T hit<k>.primID hit<k>.geomID.
TEST(AovTable, LayeredRowsGiveTheHitChannels) {
  std::vector<std::string> layered;
  for (const AovRow& row : aovTable())
    if (row.layered()) layered.push_back(layerAovName(row));
  EXPECT_EQ(layered, (std::vector<std::string>{"layers.depth", "layers.distance", "layers.primid",
                                               "layers.geomid"}));
  AovSet set(kAovNormal);
  set.layers = 2;
  EXPECT_EQ(
      exrChannelNames(set, {}),
      (std::vector<std::string>{"N.X", "N.Y", "N.Z", "hit0.Z", "hit0.T", "hit0.primID",
                                "hit0.geomID", "hit1.Z", "hit1.T", "hit1.primID", "hit1.geomID"}));
  const Framebuffer fb(2, 1, set);
  EXPECT_EQ(aovView(fb, "layers.primid").u32, fb.layerPrimId.data());
  EXPECT_EQ(aovView(fb, "layers.distance").layers, 2);
  EXPECT_EQ(fb.layerGeomId, std::vector<uint32_t>(4, kInvalidId));
  EXPECT_TRUE(std::isinf(fb.layerDistance[3]));
  EXPECT_EQ(framebufferBytesPerPixel(set), 12u + 2u * 16u);
}

/// A test-only AOV: two float channels "tuv.U", "tuv.V", -1 on a miss.
AovRow uvRow() {
  AovRow row;
  row.name = "test-uv";
  row.inAll = false;
  row.type = AovType::Float32;
  row.exrChannels = {"tuv.U", "tuv.V"};
  row.miss = -1.0;
  return row;
}

/// Its computation, which the test stands in for: channel c of pixel i is i + c / 4.
void computeUv(Framebuffer& fb, const AovRow& row) {
  std::vector<float>& v = floatPixels(fb, row);
  for (size_t i = 0; i < fb.pixelCount(); ++i)
    for (size_t c = 0; c < 2; ++c) v[2 * i + c] = float(i) + float(c) / 4.0f;
}

TEST(AovTable, ARegisteredRowIsAllocatedParsedAndListed) {
  const AovRegistration registration(uvRow());
  const AovRow& row = *findAovRow("test-uv");
  EXPECT_EQ(row.bit, registration.bit());
  EXPECT_EQ(registration.bit(), AovMask(1u << kFixedAovRows)) << "the lowest bit no fixed row uses";

  const AovSet set = parseAovSet("depth,test-uv");
  EXPECT_EQ(set.mask, AovMask(kAovDepth) | registration.bit());
  EXPECT_EQ(aovListString(set), "depth,test-uv");
  EXPECT_EQ(parseAovList("all") & registration.bit(), 0u) << "not in all";
  EXPECT_NE(test::errorOf([] { parseAovSet("test-vu"); }).find("did you mean 'test-uv'"),
            std::string::npos);

  const Framebuffer fb(3, 2, set);
  ASSERT_EQ(floatPixels(fb, row).size(), 12u);
  EXPECT_TRUE(std::all_of(floatPixels(fb, row).begin(), floatPixels(fb, row).end(), [](float v) {
    return v == -1.0f;
  })) << "allocated with its miss value";
  EXPECT_EQ(aovNames(fb), (std::vector<std::string>{"depth", "test-uv"}));
  const ImageView view = aovView(fb, "test-uv");
  EXPECT_EQ(view.channels, 2);
  EXPECT_EQ(view.f32, floatPixels(fb, row).data());
  EXPECT_EQ(view.u32, nullptr);
  EXPECT_EQ(framebufferBytesPerPixel(set), 4u + 8u);
  EXPECT_EQ(exrChannelNames(set, {}), (std::vector<std::string>{"Z", "tuv.U", "tuv.V"}));
}

TEST(AovTable, ARegisteredRowRoundTripsThroughTheExrWriterAndReader) {
  const std::string path = test::scratchDir() + "/uv.exr";
  std::vector<float> written;
  {
    const AovRegistration registration(uvRow());
    const AovRow& row = *findAovRow("test-uv");
    Framebuffer fb(4, 3, parseAovSet("depth,test-uv"));
    computeUv(fb, row);
    written = floatPixels(fb, row);
    writeExr(path, fb, ExrMetadata{});
    const std::vector<std::string> channels = readExrHeader(path).channels;
    EXPECT_EQ(channels, (std::vector<std::string>{"Z", "tuv.U", "tuv.V"}));

    const Framebuffer back = readExr(path);
    EXPECT_EQ(back.aovs, fb.aovs);
    EXPECT_EQ(floatPixels(back, row), written) << "every value as written";
    EXPECT_EQ(back.depth, fb.depth);
  }
  // Without the row the file's uv channels are no AOV; the rest reads as before.
  EXPECT_EQ(findAovRow("test-uv"), nullptr);
  const Framebuffer without = readExr(path);
  EXPECT_EQ(without.aovs, AovMask(kAovDepth));
  EXPECT_TRUE(without.registered.empty());
}

TEST(AovTable, ARegisteredUintRowRoundTripsAsUint) {
  AovRow row;
  row.name = "test-id";
  row.type = AovType::UInt32;
  row.exrChannels = {"testID"};
  row.miss = double(kInvalidId);
  const AovRegistration registration(row);
  const std::string path = test::scratchDir() + "/id.exr";
  Framebuffer fb(2, 2, parseAovSet("test-id"));
  EXPECT_EQ(uintPixels(fb, *findAovRow("test-id")),
            (std::vector<uint32_t>{kInvalidId, kInvalidId, kInvalidId, kInvalidId}));
  uintPixels(fb, *findAovRow("test-id")) = {7, 8, 9, 0xFFFFFFFEu};
  writeExr(path, fb, ExrMetadata{});
  const Framebuffer back = readExr(path);
  EXPECT_EQ(uintPixels(back, *findAovRow("test-id")), (std::vector<uint32_t>{7, 8, 9, 0xFFFFFFFEu}))
      << "UINT: a float channel would have rounded 0xFFFFFFFE";
  EXPECT_NE(parseAovList("all") & registration.bit(), 0u) << "inAll rows are in all";
}

TEST(AovTable, ARegisteredRowIsADatasetFileWithItsShape) {
  const AovRegistration registration(uvRow());
  Framebuffer fb(4, 3, parseAovSet("test-uv"));
  computeUv(fb, *findAovRow("test-uv"));
  const std::string path = test::scratchDir() + "/uv.npy";
  writeDatasetImage(path, DatasetFormat::Npy, aovView(fb, "test-uv"), "test-uv");
  const DatasetImage back = readDatasetImage(path);
  EXPECT_EQ(back.width, 4);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.channels, 2);
  EXPECT_EQ(back.f32, floatPixels(fb, *findAovRow("test-uv")));
  // A 2-channel float AOV fits no PFM; the refusal lists the rows PFM takes, without it.
  const std::string refusal = test::errorOf([] { checkDatasetAov(DatasetFormat::Pfm, "test-uv"); });
  EXPECT_NE(refusal.find("takes float AOVs of 1 or 3 channels: depth, distance, normal, "
                         "position, shading-normal;"),
            std::string::npos)
      << refusal;
}

TEST(AovTable, RegistrationRefusesTakenNamesAndChannels) {
  AovRow taken = uvRow();
  taken.name = "depth";
  EXPECT_NE(test::errorOf([&] { AovRegistration r(taken); }).find("already"), std::string::npos);
  AovRow channel = uvRow();
  channel.exrChannels = {"tuv.U", "N.X"};
  EXPECT_NE(test::errorOf([&] { AovRegistration r(channel); }).find("'N.X'"), std::string::npos);
  EXPECT_EQ(aovTable().size(), kFixedAovRows) << "a refused row is not left in the table";
}

}  // namespace
