#include "cameras/lidar/lidar.h"

#include "core/util/error.h"

namespace aperture {

LidarSensor loadLidar(const std::string& specOrPreset) {
  throw Error(cat(specOrPreset, ": LiDAR specs are not read yet"));
}

LidarRays sweepRays(const LidarSensor& sensor, const Trajectory&, int, std::optional<int64_t>) {
  throw Error(cat(sensor.name, ": sweeps are not made yet"));
}

}  // namespace aperture
