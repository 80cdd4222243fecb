// Reading LiDAR specs: each format against values written by hand, the formulas of the
// vendors' own software (ouster-sdk's XYZLut, the ROS Velodyne driver's point) written here
// independently, the presets, and the errors of bad specs.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "cameras/lidar/lidar.h"
#include "core/util/error.h"
#include "tests/lidar_support.h"

namespace aperture {
namespace {

constexpr double kPiSpec = 3.14159265358979323846;

std::string writeSpec(const std::string& name, const std::string& text) {
  return test::writeScratchFile(name, text);
}

TEST(LidarSpec, ApertureJsonGivesItsFields) {
  const std::string path = writeSpec("tiny.json", R"({
    "name": "tiny", "sweep_rate_hz": 20, "columns": 8, "spin": "counterclockwise",
    "first_column_azimuth_deg": 45, "min_range_m": 0.5, "max_range_m": 50,
    "beams": {"elevation_deg": [-10, 0, 10], "azimuth_deg": [1, 0, -1],
              "time_offset_ns": [0, 100, 200], "origin_m": [[0, 0, 0], [0.1, 0, 0], [0, 0, 0.2]],
              "range_offset_m": [0, 0.01, 0]},
    "sensor_from_lidar": [1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 1.5, 0, 0, 0, 1]})");
  const LidarSensor s = loadLidar(path);
  EXPECT_EQ(s.name, "tiny");
  EXPECT_EQ(s.kind, LidarKind::Spinning);
  ASSERT_EQ(s.beams.size(), 3u);
  EXPECT_EQ(s.beams[0].elevationDeg, -10);
  EXPECT_EQ(s.beams[2].azimuthDeg, -1);
  EXPECT_EQ(s.beams[1].timeOffsetNs, 100);
  EXPECT_EQ(s.beams[1].origin, glm::dvec3(0.1, 0, 0));
  EXPECT_EQ(s.beams[1].rangeOffset, 0.01);
  EXPECT_EQ(s.columns, 8);
  EXPECT_EQ(s.spin, 1);
  EXPECT_EQ(s.periodNs(), 50000000);
  EXPECT_EQ(s.columnTime(3), 3 * 50000000 / 8);
  EXPECT_EQ(s.columnAzimuthDeg(2), 45 + 2 * 45.0);
  EXPECT_EQ(s.minRange, 0.5);
  EXPECT_EQ(s.maxRange, 50);
  EXPECT_EQ(s.sensorFromLidar[3], glm::dvec4(0.5, 0, 1.5, 1));
  EXPECT_EQ(s.windowColumns().size(), 8u);
}

TEST(LidarSpec, BadSpecsNameTheFileAndTheField) {
  const std::string wrongLength = writeSpec("wrong.json", R"({"sweep_rate_hz": 10, "columns": 4,
    "beams": {"elevation_deg": [-1, 0, 1], "azimuth_deg": [0, 0]}})");
  std::string e = test::errorOf([&] { loadLidar(wrongLength); });
  EXPECT_NE(e.find(wrongLength), std::string::npos) << e;
  EXPECT_NE(e.find("beams.azimuth_deg"), std::string::npos) << e;
  EXPECT_NE(e.find("2 entries"), std::string::npos) << e;

  const std::string missing = writeSpec("missing.json", R"({"columns": 4,
    "beams": {"elevation_deg": [0]}})");
  e = test::errorOf([&] { loadLidar(missing); });
  EXPECT_NE(e.find(missing), std::string::npos) << e;
  EXPECT_NE(e.find("'sweep_rate_hz' is missing"), std::string::npos) << e;

  const std::string zeroRate = writeSpec("zero.json", R"({"sweep_rate_hz": 0, "columns": 4,
    "beams": {"elevation_deg": [0]}})");
  e = test::errorOf([&] { loadLidar(zeroRate); });
  EXPECT_NE(e.find("sweep_rate_hz"), std::string::npos) << e;
  EXPECT_NE(e.find(zeroRate), std::string::npos) << e;

  const std::string negColumns = writeSpec("neg.json", R"({"sweep_rate_hz": 10, "columns": -4,
    "beams": {"elevation_deg": [0]}})");
  EXPECT_NE(test::errorOf([&] { loadLidar(negColumns); }).find("'columns' must be positive"),
            std::string::npos);

  const std::string typo = writeSpec("typo.json", R"({"sweep_rate_hz": 10, "colums": 4,
    "beams": {"elevation_deg": [0]}})");
  e = test::errorOf([&] { loadLidar(typo); });
  EXPECT_NE(e.find("did you mean 'columns'"), std::string::npos) << e;

  const std::string badTime = writeSpec("time.json", R"({"sweep_rate_hz": 10, "columns": 4,
    "column_time_ns": 30000000, "beams": {"elevation_deg": [0]}})");
  EXPECT_NE(test::errorOf([&] { loadLidar(badTime); }).find("column_time_ns"), std::string::npos);

  EXPECT_NE(test::errorOf([&] { loadLidar("no/such/spec.json"); }).find("cannot open"),
            std::string::npos);
}

// ouster-sdk's XYZLut (ouster_core/src/xyzlut.cpp), written from its formula: the point of
// range r (mm) at pixel (row u, column m) of a w-column frame, in the sensor frame, metres.
glm::dvec3 ousterXyzLut(double rMm, int u, int m, int w, const std::vector<double>& alt,
                        const std::vector<double>& az, const glm::dmat4& beamToLidar,
                        const glm::dmat4& lidarToSensorMm) {
  const double thetaE = 2 * kPiSpec - m * (2 * kPiSpec / w);
  const double thetaA = -az[size_t(u)] * kPiSpec / 180;
  const double phi = alt[size_t(u)] * kPiSpec / 180;
  const glm::dvec3 d(std::cos(thetaE + thetaA) * std::cos(phi),
                     std::sin(thetaE + thetaA) * std::cos(phi), std::sin(phi));
  const double b03 = beamToLidar[3][0], b23 = beamToLidar[3][2];
  const double n = b23 != 0 ? std::sqrt(b03 * b03 + b23 * b23) : b03;
  const glm::dvec3 o(std::cos(thetaE) * b03 - d.x * n, std::sin(thetaE) * b03 - d.y * n,
                     -d.z * n + b23);
  const glm::dvec3 lidar = rMm * d + o;
  return glm::dvec3(lidarToSensorMm * glm::dvec4(lidar, 1.0)) * 0.001;
}

const char* kOusterNested = R"({
  "sensor_info": {"prod_line": "OS-1-64", "prod_sn": "1"},
  "config_params": {"lidar_mode": "512x10", "udp_port_lidar": 7502},
  "imu_intrinsics": {"imu_to_sensor_transform": [1,0,0,6.253, 0,1,0,-11.775, 0,0,1,7.645, 0,0,0,1]},
  "lidar_intrinsics": {"lidar_to_sensor_transform": [-1,0,0,0, 0,-1,0,0, 0,0,1,36.18, 0,0,0,1]},
  "beam_intrinsics": {"beam_altitude_angles": [10, 3.5, -3.5, -10],
                      "beam_azimuth_angles": [3, 1, -1, -3],
                      "lidar_origin_to_beam_origin_mm": 15.806,
                      "beam_to_lidar_transform": [1,0,0,15.806, 0,1,0,0, 0,0,1,2.5, 0,0,0,1]},
  "lidar_data_format": {"pixels_per_column": 4, "columns_per_packet": 16,
                        "columns_per_frame": 512, "pixel_shift_by_row": [9, 6, 3, 0],
                        "column_window": [0, 511], "fps": 10}
})";

TEST(LidarSpec, OusterNestedMetadataMatchesTheSdkFormula) {
  const std::string path = writeSpec("os.json", kOusterNested);
  const LidarSensor s = loadLidar(path);
  EXPECT_EQ(s.source.format, "ouster");
  ASSERT_EQ(s.beams.size(), 4u);
  EXPECT_EQ(s.columns, 512);
  EXPECT_EQ(s.sweepRateHz, 10);
  EXPECT_EQ(s.pixelShiftByRow, (std::vector<int>{9, 6, 3, 0}));
  EXPECT_EQ(s.columnWindow, (std::array<int, 2>{0, 511}));
  EXPECT_EQ(s.beams[0].azimuthDeg, -3);
  EXPECT_EQ(s.beams[3].elevationDeg, -10);
  EXPECT_NEAR(s.beams[1].rangeOffset, std::sqrt(15.806 * 15.806 + 2.5 * 2.5) * 1e-3, 1e-15);
  EXPECT_NEAR(s.sensorFromLidar[3][2], 0.03618, 1e-15);
  EXPECT_EQ(s.sensorFromLidar[0][0], -1);

  const std::vector<double> alt{10, 3.5, -3.5, -10}, az{3, 1, -1, -3};
  glm::dmat4 b2l(1.0), l2s(1.0);
  b2l[3] = {15.806, 0, 2.5, 1};
  l2s[0][0] = l2s[1][1] = -1;
  l2s[3][2] = 36.18;
  const LidarRays rays = sweepRays(s, Trajectory(), 0);
  ASSERT_EQ(rays.size(), 512u * 4u);
  for (size_t i = 0; i < rays.size(); i += 37) {
    const double rMm = 1234.5 + 7.0 * double(i % 11);
    const glm::dvec3 mine = rays.sensorPointAt(i, rMm * 1e-3 - rays.rangeOffset[i]);
    const glm::dvec3 sdk =
        ousterXyzLut(rMm, int(rays.ring[i]), int(rays.column[i]), 512, alt, az, b2l, l2s);
    EXPECT_LT(glm::length(mine - sdk), 1e-7) << "ray " << i;
  }
}

TEST(LidarSpec, OusterLegacyMetadataTakesTheSdkDefaults) {
  const std::string path = writeSpec("legacy.json", R"({
    "prod_line": "OS-1-16-A0", "lidar_mode": "1024x10",
    "beam_altitude_angles": [2, 1, -1, -2], "beam_azimuth_angles": [0.5, 0.5, -0.5, -0.5],
    "lidar_origin_to_beam_origin_mm": 12.163,
    "data_format": {"columns_per_frame": 1024, "pixels_per_column": 4,
                    "pixel_shift_by_row": [0, 6, 12, 18], "column_window": [1000, 23]}})");
  const LidarSensor s = loadLidar(path);
  ASSERT_EQ(s.beams.size(), 4u);
  EXPECT_EQ(s.columns, 1024);
  EXPECT_EQ(s.sweepRateHz, 10);
  EXPECT_EQ(s.beams[2].origin, glm::dvec3(0.012163, 0, 0));
  EXPECT_EQ(s.beams[2].rangeOffset, 0.012163);
  // ouster-sdk's DEFAULT_LIDAR_TO_SENSOR when the file has none.
  EXPECT_NEAR(s.sensorFromLidar[3][2], 0.03618, 1e-15);
  // A window across the frame's end: ids 0..23 and 1000..1023, in firing order.
  const std::vector<int> ids = s.windowColumns();
  ASSERT_EQ(ids.size(), 48u);
  EXPECT_EQ(ids.front(), 0);
  EXPECT_EQ(ids[23], 23);
  EXPECT_EQ(ids[24], 1000);
  EXPECT_EQ(ids.back(), 1023);

  const std::string bad = writeSpec("bad_ouster.json", R"({"lidar_mode": "1024x10",
    "beam_altitude_angles": [2, 1, -1], "beam_azimuth_angles": [0, 0]})");
  const std::string e = test::errorOf([&] { loadLidar(bad); });
  EXPECT_NE(e.find(bad), std::string::npos) << e;
  EXPECT_NE(e.find("beam_azimuth_angles"), std::string::npos) << e;
}

// The ROS velodyne_pointcloud driver's point (rawdata.cc), written from its formula: laser
// with vertical angle v, rotation correction rc, offsets vo, ho, at encoder rotation rot
// (radians) and corrected distance d, in ROS axes.
glm::dvec3 velodyneDriverPoint(double d, double rot, double v, double rc, double vo, double ho) {
  const double a = rot - rc;
  const double xy = d * std::cos(v) - vo * std::sin(v);
  const double xx = xy * std::sin(a) - ho * std::cos(a);
  const double yy = xy * std::cos(a) + ho * std::sin(a);
  const double z = d * std::sin(v) + vo * std::cos(v);
  return {yy, -xx, z};
}

TEST(LidarSpec, VelodyneCalibrationMatchesTheDriverFormula) {
  const std::string path = writeSpec("cal.yaml", R"(lasers:
- {dist_correction: 1.2, dist_correction_x: 0.0, dist_correction_y: 0.0, focal_distance: 0.0,
  focal_slope: 0.0, horiz_offset_correction: 0.03, laser_id: 1, rot_correction: -0.05,
  vert_correction: 0.1, vert_offset_correction: 0.2}
- {dist_correction: 0.0, horiz_offset_correction: -0.026, laser_id: 0, rot_correction: 0.08,
  vert_correction: -0.2, vert_offset_correction: 0.15}
num_lasers: 2
distance_resolution: 0.002
)");
  const LidarSensor s = loadLidar(path);
  EXPECT_EQ(s.source.format, "velodyne");
  ASSERT_EQ(s.beams.size(), 2u);
  EXPECT_NEAR(s.beams[0].elevationDeg, -0.2 * 180 / kPiSpec, 1e-12);
  EXPECT_NEAR(s.beams[1].azimuthDeg, -0.05 * 180 / kPiSpec, 1e-12);
  EXPECT_EQ(s.beams[1].distCorrection, 1.2);
  const double v[2] = {-0.2, 0.1}, rc[2] = {0.08, -0.05}, vo[2] = {0.15, 0.2},
               ho[2] = {-0.026, 0.03};
  const LidarRays rays = sweepRays(s, Trajectory(), 0);
  ASSERT_EQ(rays.size(), size_t(s.columns) * 2);
  for (size_t i = 0; i < rays.size(); i += 13) {
    const int b = int(rays.ring[i]);
    const double rot = rays.column[i] * 2 * kPiSpec / s.columns;  // the encoder's rotation
    const double d = 3.0 + 0.01 * double(i % 17);
    const glm::dvec3 driver = velodyneDriverPoint(d, rot, v[b], rc[b], vo[b], ho[b]);
    EXPECT_LT(glm::length(rays.sensorPointAt(i, d) - driver), 1e-12) << "ray " << i;
  }

  const std::string repeated = writeSpec("rep.yaml", R"(lasers:
- {laser_id: 0, rot_correction: 0, vert_correction: 0}
- {laser_id: 0, rot_correction: 0, vert_correction: 0.1}
)");
  const std::string e = test::errorOf([&] { loadLidar(repeated); });
  EXPECT_NE(e.find("lasers[1].laser_id"), std::string::npos) << e;
}

TEST(LidarSpec, LivoxCsvGivesTimesAndElevations) {
  const std::string path = writeSpec("scan.csv",
                                     "Time/s,Azimuth/deg,Zenith/deg\n"
                                     "0,0,90\n0.00001,10,80\n0.00002,-10,100\n");
  const LidarSensor s = loadLidar(path);
  EXPECT_EQ(s.kind, LidarKind::Pattern);
  ASSERT_EQ(s.pattern.size(), 3u);
  EXPECT_EQ(s.pattern[1].timeNs, 10000);
  EXPECT_EQ(s.pattern[2].timeNs, 20000);
  EXPECT_EQ(s.pattern[1].azimuthDeg, 10);
  EXPECT_EQ(s.pattern[1].elevationDeg, 10);
  EXPECT_EQ(s.pattern[2].elevationDeg, -10);
  EXPECT_EQ(s.patternPeriodNs, 30000);  // the span and one mean step

  // livox_laser_simulation aims at yaw = azimuth, pitch = zenith − 90° (Gazebo: Rz·Ry·x).
  const LidarRays rays = sweepRays(s, Trajectory(), 0);
  ASSERT_GT(rays.size(), 3u);
  const double yaw = 10 * kPiSpec / 180, pitch = (80 - 90) * kPiSpec / 180;
  const glm::dvec3 gazebo(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch),
                          -std::sin(pitch));
  EXPECT_LT(glm::length(rays.direction[1] - gazebo), 1e-15);

  const std::string spec = writeSpec("livox.json",
                                     R"({"name": "mid", "pattern_csv": "scan.csv",
                                         "sweep_rate_hz": 10, "pattern_period_s": 0.001})");
  const LidarSensor viaSpec = loadLidar(spec);
  EXPECT_EQ(viaSpec.name, "mid");
  EXPECT_EQ(viaSpec.patternPeriodNs, 1000000);
  EXPECT_EQ(viaSpec.pattern.size(), 3u);

  const std::string short_ = writeSpec("short.csv", "t,a,z\n0,1\n");
  EXPECT_NE(test::errorOf([&] { loadLidar(short_); }).find("short.csv line 2"), std::string::npos);
}

TEST(LidarSpec, SpecsStartFromAVendorFileAndOverrideItsFields) {
  writeSpec("os.json", kOusterNested);
  const std::string spec = writeSpec("mine.json", R"({"name": "os-fast", "from": "os.json",
    "sweep_rate_hz": 20, "max_range_m": 40,
    "beams": {"time_offset_ns": [0, 10, 20, 30]},
    "sensor_from_lidar": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]})");
  const LidarSensor s = loadLidar(spec);
  EXPECT_EQ(s.name, "os-fast");
  EXPECT_EQ(s.source.path, spec);
  EXPECT_EQ(s.sweepRateHz, 20);
  EXPECT_EQ(s.maxRange, 40);
  EXPECT_EQ(s.columns, 512);               // from the metadata
  EXPECT_EQ(s.beams[2].azimuthDeg, 1);     // from the metadata, negated
  EXPECT_EQ(s.beams[3].timeOffsetNs, 30);  // given over it
  EXPECT_EQ(s.sensorFromLidar, glm::dmat4(1.0));

  const std::string wrongLength = writeSpec("short.json", R"({"from": "os.json",
    "beams": {"time_offset_ns": [0, 10]}})");
  std::string e = test::errorOf([&] { loadLidar(wrongLength); });
  EXPECT_NE(e.find("beams.time_offset_ns"), std::string::npos) << e;
  EXPECT_NE(e.find("the beam table 4"), std::string::npos) << e;

  const std::string twoBases = writeSpec("two.json", R"({"from": "os.json",
    "pattern": [[0, 0, 0]]})");
  EXPECT_NE(test::errorOf([&] { loadLidar(twoBases); }).find("give one of"), std::string::npos);
  const std::string wrongType = writeSpec("type.json", R"({"from": "os.json", "type": "pattern"})");
  EXPECT_NE(test::errorOf([&] { loadLidar(wrongType); }).find("'type'"), std::string::npos);
}

TEST(LidarSpec, PresetsLoadWithTheirBeamCountsAndCiteTheirSources) {
  const std::vector<std::pair<std::string, size_t>> expected{
      {"VLP-16", 16}, {"HDL-32E", 32}, {"HDL-64E", 64}, {"OS1-64", 64}, {"OS1-128", 128}};
  for (const auto& [name, beams] : expected) {
    SCOPED_TRACE(name);
    const LidarSensor s = loadLidar(name);
    EXPECT_EQ(s.name, name);
    EXPECT_EQ(s.beams.size(), beams);
    EXPECT_GT(s.columns, 0);
    const nlohmann::json doc = nlohmann::json::parse(lidarPresetText(name));
    ASSERT_TRUE(doc.contains("source"));
    EXPECT_GT(doc["source"].dump().size(), 40u);
  }
  EXPECT_EQ(lidarPresetNames().size(), expected.size());
  // VLP-16: the manual's 2.304 µs between lasers and 55.296 µs between sequences.
  const LidarSensor vlp = loadLidar("VLP-16");
  EXPECT_EQ(vlp.beams[5].timeOffsetNs, 5 * 2304);
  EXPECT_EQ(vlp.columnTime(10), 10 * 55296);
  EXPECT_NEAR(vlp.beams[0].elevationDeg, -15, 1e-9);
  EXPECT_NEAR(vlp.beams[1].elevationDeg, 1, 1e-9);
  const LidarSensor os = loadLidar("OS1-128");
  EXPECT_EQ(os.columns, 1024);
  EXPECT_EQ(os.pixelShiftByRow.size(), 128u);
  // Row 0 is the table's first entry, Ouster's highest beam.
  for (size_t i = 1; i < os.beams.size(); ++i)
    EXPECT_GT(os.beams[0].elevationDeg, os.beams[i].elevationDeg);

  const std::string e = test::errorOf([] { loadLidar("VLP16"); });
  EXPECT_NE(e.find("did you mean 'VLP-16'"), std::string::npos) << e;
}

}  // namespace
}  // namespace aperture
