// The packet contract of core/engine/camera.h: which pixel each lane of a packet covers, and which
// lanes of a tail block fall outside the image. Expectations are written out pixel by pixel.
// And the gate of core/engine/packet.h every packet passes into Embree (sealLanes).
#include <gtest/gtest.h>

#include <limits>
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

namespace {

/// Lane k of a packet of width N after sealLanes, from rays chosen to cover each way a ray
/// can be untraceable, each lane given valid −1 or 0 in turn.
template <int N>
void checkSealAtWidth() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  struct Ray {
    float org[3], dir[3], tnear, tfar;
    bool traceable;  // by Embree's documentation (RTCRay) and its range (1.844e18)
  };
  const std::vector<Ray> rays = {
      {{0, 0, 4}, {0, 0, -1}, 0, inf, true},      {{1, 2, 3}, {0, 1, 0}, 0.5f, 2, true},
      {{0, 0, 4}, {0, 0, -1}, 3, 3, true},        {{nan, 0, 4}, {0, 0, -1}, 0, inf, false},
      {{0, 0, 4}, {0, inf, -1}, 0, inf, false},   {{0, -inf, 4}, {0, 0, -1}, 0, inf, false},
      {{1e19f, 0, 4}, {0, 0, -1}, 0, inf, false}, {{0, 0, 4}, {0, 0, -2e18f}, 0, inf, false},
      {{0, 0, 4}, {0, 0, -1}, -1, inf, false},    {{0, 0, 4}, {0, 0, -1}, 2, 1, false},
      {{0, 0, 4}, {0, 0, -1}, nan, inf, false},   {{0, 0, 4}, {0, 0, -1}, 0, nan, false},
      {{0, 0, 4}, {nan, nan, nan}, 0, inf, false}};
  size_t next = 0;
  for (int round = 0; round < int(2 * rays.size()); ++round) {
    PacketBuffers<N> p;
    std::vector<size_t> which(N);
    std::vector<int> given(N);
    for (int k = 0; k < N; ++k) {
      which[size_t(k)] = next % rays.size();
      given[size_t(k)] = (next / rays.size() + size_t(k)) % 2 ? 0 : -1;
      ++next;
      const Ray& r = rays[which[size_t(k)]];
      RayLanes& l = p.lanes;
      l.orgX[k] = r.org[0], l.orgY[k] = r.org[1], l.orgZ[k] = r.org[2];
      l.dirX[k] = r.dir[0], l.dirY[k] = r.dir[1], l.dirZ[k] = r.dir[2];
      l.tnear[k] = r.tnear, l.tfar[k] = r.tfar;
      p.valid[k] = given[size_t(k)];
    }
    const int active = sealLanes<N>(p.valid, p.lanes);
    int expected = 0;
    for (int k = 0; k < N; ++k) {
      const Ray& r = rays[which[size_t(k)]];
      const bool on = given[size_t(k)] != 0 && r.traceable;
      expected += on;
      SCOPED_TRACE(::testing::Message() << "width " << N << ", lane " << k << ", ray "
                                        << which[size_t(k)] << ", valid " << given[size_t(k)]);
      EXPECT_EQ(p.valid[k], on ? -1 : 0);
      if (on) {  // untouched
        EXPECT_EQ(p.lanes.tnear[k], r.tnear);
        EXPECT_EQ(p.lanes.tfar[k], r.tfar);
      } else {  // inactive in a ray stream too
        EXPECT_LT(p.lanes.tfar[k], p.lanes.tnear[k]);
      }
    }
    EXPECT_EQ(active, expected);
  }
}

}  // namespace

TEST(PacketGate, OnlyRaysEmbreeTakesStayActiveAndEveryOtherLaneIsAnEmptySegment) {
  checkSealAtWidth<1>();
  checkSealAtWidth<4>();
  checkSealAtWidth<8>();
  checkSealAtWidth<16>();
}
