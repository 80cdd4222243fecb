// Direction tables (cameras/lenses/direction_table.h) under --max-memory: a table's bytes known
// from the sensor's size alone, the peak counting each sensor once, and the render command
// refusing a table that does not fit while the same camera without distortion renders.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "cameras/lenses/direction_table.h"
#include "tests/support.h"

namespace aperture {
namespace {

using test::apertureBinary;
using test::runCommand;
using test::scratchDir;

// --max-memory counts the direction tables of distorted lenses: a table's bytes are known
// from the sensor's size alone, each sensor counts once, and the cache bounds the rest.
TEST(DirectionTableMemory, BytesForIsWhatATableHolds) {
  for (const glm::ivec2 size : {glm::ivec2(64, 48), glm::ivec2(37, 23), glm::ivec2(1, 1)}) {
    CalibratedSensor s;
    s.width = size.x, s.height = size.y;
    s.lens = Lens(LensModelId::OpenCV, {50, 50, size.x / 2.0, size.y / 2.0, -0.1, 0.01, 0, 0});
    EXPECT_EQ(DirectionTable::bytesFor(size.x, size.y), DirectionTable(s).bytes())
        << size.x << "x" << size.y;
  }
}

TEST(DirectionTableMemory, PeakCountsEachSensorOnceUpToTheCacheAndTheLargest) {
  auto sensor = [](int width, int height, double k1) {
    CalibratedSensor s;
    s.width = width, s.height = height;
    s.lens = Lens(LensModelId::SimpleRadial, {1000, width / 2.0, height / 2.0, k1});
    return s;
  };
  const size_t hd = DirectionTable::bytesFor(1920, 1080);
  // The same sensor twice counts once; another lens or size counts again.
  EXPECT_EQ(DirectionTable::peakBytes({sensor(1920, 1080, -0.1), sensor(1920, 1080, -0.1)}), hd);
  EXPECT_EQ(DirectionTable::peakBytes({sensor(1920, 1080, -0.1), sensor(1920, 1080, -0.2)}),
            2 * hd);
  // Far more sensors than the cache keeps: its bound plus the largest, computed beside it.
  std::vector<CalibratedSensor> many;
  for (int k = 0; k < 60; ++k) many.push_back(sensor(1920, 1080, -0.1 - 0.001 * k));
  many.push_back(sensor(4000, 3000, -0.1));
  EXPECT_EQ(DirectionTable::peakBytes(many),
            DirectionTable::kCacheBytes + DirectionTable::bytesFor(4000, 3000));
  EXPECT_EQ(DirectionTable::peakBytes({}), 0u);
}

// The render command refuses a distorted 12 Mpx camera whose table (313 MB) does not fit the
// limit, naming the tables; the same camera without distortion (no table) renders.
TEST(DirectionTableMemory, MaxMemoryRefusesATableThatDoesNotFit) {
  const std::string dir = scratchDir();
  const std::string camera =
      " --quiet --mesh procedural:sphere --size 4000,3000 --aov depth --eye 0,0,5 --at 0,0,0"
      " --intrinsics 3000,3000,2000,1500 --max-memory 200M --out " +
      dir + "/out.exr";
  std::string out;
  EXPECT_EQ(runCommand(apertureBinary() + " render" + camera +
                           " --lens-model OPENCV --distortion -0.1,0.01,0,0",
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("lens direction tables 313.5 MB"), std::string::npos) << out;
  EXPECT_NE(out.find("--max-memory 200M"), std::string::npos) << out;
  EXPECT_EQ(runCommand(apertureBinary() + " render" + camera + " --lens-model PINHOLE", &out), 0)
      << out;
}

}  // namespace
}  // namespace aperture
