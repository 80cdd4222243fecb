#include <gtest/gtest.h>

#include <cmath>

#include "core/aov/framebuffer.h"
#include "core/util/error.h"

using namespace aperture;

TEST(Aov, ParsesListsAndRejectsUnknownNames) {
  EXPECT_EQ(parseAovList("color,depth"), AovMask(kAovColor | kAovDepth));
  EXPECT_EQ(parseAovList("all"), AovMask(0x7f));
  EXPECT_EQ(aovListString(kAovNormal | kAovPrimId), "normal,primid");
  try {
    parseAovList("color,dpeth");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("dpeth"), std::string::npos);
  }
}

TEST(Framebuffer, AllocatesOnlyRequestedAovsWithMissValues) {
  Framebuffer fb(3, 2, kAovDepth | kAovGeomId);
  EXPECT_TRUE(fb.rgba.empty());
  EXPECT_TRUE(fb.normal.empty());
  ASSERT_EQ(fb.depth.size(), 6u);
  EXPECT_TRUE(std::isinf(fb.depth[5]));
  EXPECT_EQ(fb.geomId[0], kInvalidId);
}
