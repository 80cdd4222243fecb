// The packet contract of core/engine/camera.h: which pixel each lane of a packet covers, and which
// lanes of a tail block fall outside the image. Expectations are written out pixel by pixel.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "core/engine/camera.h"
#include "core/engine/packet.h"

using namespace aperture;

namespace {

using Pixels = std::vector<std::pair<int, int>>;  // (row, column) per lane

Pixels lanePixels(const PacketRequest& req) {
  Pixels out;
  for (int k = 0; k < req.lanes(); ++k) {
    const LanePixel p = req.pixel(k);
    EXPECT_EQ(p.row, lanePixel(req.x0, req.y0, req.blockW, k).row);
    EXPECT_EQ(p.column, lanePixel(req.x0, req.y0, req.blockW, k).column);
    out.emplace_back(p.row, p.column);
  }
  return out;
}

}  // namespace

TEST(PacketContract, LanesRunAlongTheRowsOfTheBlock) {
  // 4x2 (8 lanes) at column 8, row 4.
  const Pixels fourByTwo = {{4, 8}, {4, 9}, {4, 10}, {4, 11}, {5, 8}, {5, 9}, {5, 10}, {5, 11}};
  EXPECT_EQ(lanePixels({8, 4, 4, 2, 0}), fourByTwo);
  // 2x2 at column 2, row 6; 1x1 at column 5, row 3; 4x4 at the origin.
  EXPECT_EQ(lanePixels({2, 6, 2, 2, 0}), (Pixels{{6, 2}, {6, 3}, {7, 2}, {7, 3}}));
  EXPECT_EQ(lanePixels({5, 3, 1, 1, 0}), (Pixels{{3, 5}}));
  const Pixels fourByFour = {{0, 0}, {0, 1}, {0, 2}, {0, 3}, {1, 0}, {1, 1}, {1, 2}, {1, 3},
                             {2, 0}, {2, 1}, {2, 2}, {2, 3}, {3, 0}, {3, 1}, {3, 2}, {3, 3}};
  EXPECT_EQ(lanePixels({0, 0, 4, 4, PacketRequest::kCentreRay}), fourByFour);
  // The block shapes of the frame loop hold exactly the packet's lanes.
  for (int n : {1, 4, 8, 16}) EXPECT_EQ(blockWidthFor(n) * blockHeightFor(n), n);
  // The other convention (lanes down the columns) would be caught.
  Pixels columnMajor;
  for (int k = 0; k < 8; ++k) columnMajor.emplace_back(4 + k % 2, 8 + k / 2);
  EXPECT_NE(columnMajor, fourByTwo);
}

TEST(PacketContract, TailLanesOutsideTheImageAreTheOnlyOnesOut) {
  // A 13 x 7 image: the 4x4 block at column 12, row 4 keeps column 12 and rows 4..6 only.
  const PacketRequest tail{12, 4, 4, 4, 0};
  std::vector<int> inside;
  for (int k = 0; k < tail.lanes(); ++k)
    if (tail.inImage(k, 13, 7)) inside.push_back(k);
  EXPECT_EQ(inside, (std::vector<int>{0, 4, 8}));
  // Lane 1 is column 13 = width and lane 12 row 7 = height: just outside, not inside.
  EXPECT_FALSE(laneInImage(12, 4, 4, 1, 13, 7));
  EXPECT_FALSE(laneInImage(12, 4, 4, 12, 13, 7));
  EXPECT_TRUE((LanePixel{6, 12}.inImage(13, 7)));
  EXPECT_FALSE((LanePixel{7, 12}.inImage(13, 7)));
  // A block inside the image keeps every lane.
  const PacketRequest full{8, 0, 4, 4, 0};
  for (int k = 0; k < full.lanes(); ++k) EXPECT_TRUE(full.inImage(k, 13, 7)) << k;
}
