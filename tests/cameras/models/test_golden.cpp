// Golden hashes of every camera's rays and images, taken before the parameter redesign (issue
// 10) and the ray-generation rewrite (issue 13): both must leave every ray and every pixel
// bit-identical. Images are rendered with Embree pinned to SSE4.2 kernels
// (APERTURE_EMBREE_CONFIG), so the hashes do not depend on the CPU's vector width. They still
// depend on its vendor: Embree's ray distances start from the approximate reciprocal (rcpps),
// which Intel and AMD round differently, so t and what follows from it (depth, distance,
// position) differ in their last bits. Each vendor has its own image file, both taken from
// the build before the vectorisation (ff24ca4); every other AOV must agree between them.
// Geometry AOVs of spp > 1 cameras are not in the golden set: they come from the pixel-centre
// ray by design since issue 10; colour at spp > 1 is.
//
// Regenerate (only when a change of the images is intended and explained in the commit):
//   APERTURE_UPDATE_GOLDEN=1 build/tests/aperture_tests --gtest_filter='Golden.*'
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "core/exr/exr.h"
#include "tests/support.h"

using namespace aperture;

namespace {

struct GoldenCase {
  const char* name;
  const char* flags;             ///< camera flags exactly as a user types them
  bool geometryIsGolden = true;  ///< false for spp > 1: only colour is compared
};

// Every camera model and every way of giving its parameters. The eye looks at the default
// procedural scene (spheres on a ground plane, about 10 units across).
const GoldenCase kCases[] = {
    {"perspective_fov", "--camera perspective --eye 0.3,3,12 --at 0,0.5,0 --fov 40"},
    {"perspective_fov_x", "--eye 0.3,3,12 --at 0,0.5,0 --fov 50 --fov-axis x"},
    {"perspective_fov_diagonal", "--eye 0.3,3,12 --at 0,0.5,0 --fov 50 --fov-axis diagonal"},
    {"perspective_default_fov", "--eye 0.3,3,12 --at 0,0.5,0"},
    {"perspective_focal_length", "--eye 0.3,3,12 --at 0,0.5,0 --focal-length 35"},
    {"perspective_focal_sensor", "--eye 0.3,3,12 --at 0,0.5,0 --focal-length 50 --sensor 24,36"},
    {"perspective_d_viewport", "--eye 0.3,3,12 --at 0,0.5,0 --d 2 --viewport 1.2,0.9"},
    {"perspective_viewport_only", "--eye 0.3,3,12 --at 0,0.5,0 --viewport 0.8,0.6"},
    {"perspective_shift", "--eye 0.3,3,12 --at 0,0.5,0 --fov 40 --shift 0.1,-0.2"},
    {"perspective_architectural", "--eye 0.3,3,12 --at 0,0,0 --fov 40 --architectural"},
    {"perspective_dir_up_z", "--eye 0.3,12,3 --dir 0,-1,-0.2 --up 0,0,-1 --fov 60"},
    {"perspective_spp4", "--eye 0.3,3,12 --at 0,0.5,0 --fov 40 --spp 4", false},
    {"orthographic", "--camera orthographic --eye 0.3,3,12 --at 0,0.5,0 --viewport 12,8"},
    {"oblique_dir",
     "--camera oblique --eye 0.3,3,12 --at 0,0.5,0 --viewport 12,8 "
     "--oblique-dir 0.3,-0.2,-1"},
    {"oblique_angles",
     "--camera oblique --eye 0.3,3,12 --at 0,0.5,0 --viewport 12,8 "
     "--oblique-angles 20,10"},
    {"thinlens_spp1",
     "--camera thinlens --eye 0.3,3,12 --at 0,0.5,0 --fov 40 --aperture 0.2 "
     "--focus 12"},
    {"thinlens_spp4",
     "--camera thinlens --eye 0.3,3,12 --at 0,0.5,0 --fov 40 --aperture 0.2 "
     "--focus 12 --spp 4",
     false},
    {"thinlens_shift",
     "--camera thinlens --eye 0.3,3,12 --at 0,0.5,0 --fov 40 --aperture 0.1 "
     "--focus 10 --shift 0,0.1"},
    {"equirect", "--camera equirect --eye 0.2,1,0.3 --dir 0,0,-1"},
    {"equirect_ranges",
     "--camera equirect --eye 0.2,1,0.3 --dir 0,0,-1 --lon -90,120 "
     "--lat -30,60"},
    {"fisheye_180", "--camera fisheye --eye 0.2,1,0.3 --dir 0,-0.3,-1 --fisheye-fov 180"},
    {"fisheye_230", "--camera fisheye --eye 0.2,1,0.3 --dir 0,-0.3,-1 --fisheye-fov 230"},
    // Added before the issue 13 vectorisation: clip planes and the calibrated cameras of
    // issue 11 (the ray-buffer hashes of every camera, taken first).
    {"perspective_clip", "--eye 0.3,3,12 --at 0,0.5,0 --fov 40 --clip 8,14"},
    {"calibrated_pinhole", "--intrinsics 70,72,30.5,22 --eye 0.3,3,12 --at 0,0.5,0"},
    {"calibrated_opencv",
     "--intrinsics 70,72,30.5,22 --eye 0.3,3,12 --at 0,0.5,0 --lens-model OPENCV "
     "--distortion -0.2,0.05,1e-3,-2e-3"},
    {"calibrated_full_opencv",
     "--intrinsics 70,72,30.5,22 --eye 0.3,3,12 --at 0,0.5,0 --lens-model FULL_OPENCV "
     "--distortion -0.2,0.05,1e-3,-2e-3,0.01,0.02,0.001,0.003"},
    {"calibrated_opencv_fisheye",
     "--intrinsics 25,25,30.5,22 --eye 0.2,1,0.3 --dir 0,-0.3,-1 --lens-model OPENCV_FISHEYE "
     "--distortion 0.05,-0.01,0.002,-0.0005"},
    {"calibrated_radial_fold",
     "--intrinsics 30,30,30.5,22 --eye 0.3,3,12 --at 0,0.5,0 --lens-model SIMPLE_RADIAL "
     "--distortion -0.3"},
};

// Odd sizes: tail blocks with lanes outside the image.
const char* kRaySize = "61,45";
const char* kImageSize = "93,61";

std::string goldenPath(const std::string& file) {
  return std::string(APERTURE_TESTS_DIR) + "/data/golden/" + file;
}

/// The vendors with golden images of their own (see the top of this file).
const char* const kVendors[] = {"amd", "intel"};

/// This CPU's vendor, as kVendors names it; empty for another.
std::string cpuVendor() {
  __builtin_cpu_init();
  if (__builtin_cpu_is("amd")) return "amd";
  if (__builtin_cpu_is("intel")) return "intel";
  return "";
}

bool updating() {
  const char* v = std::getenv("APERTURE_UPDATE_GOLDEN");
  return v && std::strcmp(v, "1") == 0;
}

std::map<std::string, std::string> readGolden(const std::string& file) {
  std::map<std::string, std::string> m;
  std::ifstream in(goldenPath(file));
  std::string key, value;
  while (in >> key >> value) m[key] = value;
  return m;
}

void writeGolden(const std::string& file, const std::map<std::string, std::string>& m) {
  std::ofstream out(goldenPath(file));
  for (const auto& [k, v] : m) out << k << ' ' << v << '\n';
}

/// Hashes every ray of every sample of the camera, generated in blocks of bw x bh lanes,
/// in pixel order (so any block shape gives the same hash when the rays are equal).
std::string hashRays(const CameraBase& cam, int bw, int bh, bool intervals = false) {
  const CameraDescription d = cam.describe();
  const int w = d.width, h = d.height;
  test::Fnv1a hash;
  std::vector<float> org(size_t(w) * h * 3), dir(size_t(w) * h * 3);
  std::vector<int> validity(size_t(w) * h);
  std::vector<float> interval(intervals ? size_t(w) * h * 2 : 0);
  alignas(64) float ox[16], oy[16], oz[16], dx[16], dy[16], dz[16], tn[16], tf[16], tm[16];
  alignas(64) unsigned mask[16], id[16], flags[16];
  alignas(64) int valid[16];
  RayLanes lanes{bw * bh, ox, oy, oz, tn, dx, dy, dz, tm, tf, mask, id, flags};
  for (int s = 0; s < d.spp; ++s) {
    for (int y0 = 0; y0 < h; y0 += bh)
      for (int x0 = 0; x0 < w; x0 += bw) {
        const PacketRequest req{x0, y0, bw, bh, s};
        cam.generate(req, lanes, valid);
        for (int k = 0; k < req.lanes(); ++k) {
          if (!req.inImage(k, w, h)) continue;
          const size_t p = size_t(req.pixel(k).row) * w + size_t(req.pixel(k).column);
          org[3 * p] = ox[k], org[3 * p + 1] = oy[k], org[3 * p + 2] = oz[k];
          dir[3 * p] = dx[k], dir[3 * p + 1] = dy[k], dir[3 * p + 2] = dz[k];
          validity[p] = valid[k] != 0;
          // Rays of invalid lanes are unspecified (finite); only their validity is golden.
          if (!validity[p]) std::fill_n(&org[3 * p], 3, 0.0f), std::fill_n(&dir[3 * p], 3, 0.0f);
          if (intervals)
            interval[2 * p] = validity[p] ? tn[k] : 0,
                         interval[2 * p + 1] = validity[p] ? tf[k] : 0;
        }
      }
    hash.add(org.data(), org.size() * sizeof(float));
    hash.add(dir.data(), dir.size() * sizeof(float));
    hash.add(validity.data(), validity.size() * sizeof(int));
    hash.add(interval.data(), interval.size() * sizeof(float));
  }
  return hash.hex();
}

TEST(Golden, RaysOfEveryCameraAreUnchanged) {
  std::map<std::string, std::string> got;
  for (const GoldenCase& c : kCases) {
    SCOPED_TRACE(c.name);
    const CameraParams params =
        test::cameraParamsFromFlags(std::string(c.flags) + " --size " + kRaySize);
    // A render origin away from zero, as for a mesh whose bounding box is off-centre.
    const auto cam = makeCameraModel(params, glm::dvec3(0.25, -0.5, 0.75));
    const std::string packet = hashRays(*cam, 4, 4);
    EXPECT_EQ(packet, hashRays(*cam, 1, 1)) << "16-wide packets differ from single rays";
    EXPECT_EQ(packet, hashRays(*cam, 4, 2)) << "8-wide packets differ from 16-wide ones";
    got[c.name] = packet;
    // tnear and tfar are only set by the clip planes: hashed for those cases (the hashes of
    // the others predate them).
    if (std::strstr(c.flags, "--clip")) {
      const std::string withIntervals = hashRays(*cam, 4, 4, true);
      EXPECT_EQ(withIntervals, hashRays(*cam, 1, 1, true)) << "ray intervals differ by packet";
      got[std::string(c.name) + ".intervals"] = withIntervals;
    }
  }
  if (updating()) return writeGolden("rays.txt", got);
  const auto want = readGolden("rays.txt");
  ASSERT_EQ(want.size(), got.size()) << goldenPath("rays.txt") << " is missing cases";
  for (const auto& [name, hash] : got) EXPECT_EQ(want.at(name), hash) << name;
}

/// Per-AOV hashes of an EXR's pixels (headers excluded).
std::map<std::string, std::string> aovHashes(const std::string& exr, bool geometry) {
  const Framebuffer fb = readExr(exr);
  std::map<std::string, std::string> m;
  auto add = [&](const char* name, const void* data, size_t bytes) {
    test::Fnv1a h;
    h.add(data, bytes);
    m[name] = h.hex();
  };
  add("color", fb.rgba.data(), fb.rgba.size() * sizeof(float));
  if (!geometry) return m;
  add("depth", fb.depth.data(), fb.depth.size() * sizeof(float));
  add("distance", fb.distance.data(), fb.distance.size() * sizeof(float));
  add("normal", fb.normal.data(), fb.normal.size() * sizeof(float));
  add("position", fb.position.data(), fb.position.size() * sizeof(float));
  add("primid", fb.primId.data(), fb.primId.size() * sizeof(uint32_t));
  add("geomid", fb.geomId.data(), fb.geomId.size() * sizeof(uint32_t));
  return m;
}

/// The image golden file of `vendor`: images_<scene>.<vendor>.txt.
std::string imageGoldenFile(const char* scene, const std::string& vendor) {
  return std::string("images_") + scene + "." + vendor + ".txt";
}

/// Whether an image hash's AOV follows from Embree's ray distance (depth, distance, position):
/// the AOVs whose hashes differ by vendor.
bool followsFromDistance(const std::string& name) {
  for (const char* aov : {".depth", ".distance", ".position"}) {
    const size_t n = std::strlen(aov);
    if (name.size() > n && name.compare(name.size() - n, n, aov) == 0) return true;
  }
  return false;
}

void checkImages(const std::string& mesh, const char* scene) {
  const std::string vendor = cpuVendor();
  ASSERT_FALSE(vendor.empty()) << "no golden images for this CPU's vendor: generate "
                               << goldenPath(imageGoldenFile(scene, "<vendor>"))
                               << " from the build of ff24ca4 (see the top of this file)";
  const std::string goldenFile = imageGoldenFile(scene, vendor);
  const std::string dir = test::scratchDir();
  std::map<std::string, std::string> got;
  for (const GoldenCase& c : kCases) {
    const std::string out = dir + "/" + c.name + ".exr";
    const std::string cmd = "APERTURE_EMBREE_CONFIG=isa=sse4.2 " + test::apertureBinary() +
                            " render --quiet --mesh '" + mesh + "' " + c.flags + " --size " +
                            kImageSize + " --aov all --packet 4 --out " + out;
    std::string log;
    ASSERT_EQ(test::runCommand(cmd, &log), 0) << cmd << "\n" << log;
    for (const auto& [aov, hash] : aovHashes(out, c.geometryIsGolden))
      got[std::string(c.name) + "." + aov] = hash;
  }
  if (updating()) return writeGolden(goldenFile, got);
  const auto want = readGolden(goldenFile);
  ASSERT_EQ(want.size(), got.size()) << goldenPath(goldenFile) << " is missing cases";
  for (const auto& [name, hash] : got) EXPECT_EQ(want.at(name), hash) << name;
}

TEST(Golden, ImagesOfEveryCameraAreUnchangedOnTheDefaultScene) {
  checkImages("procedural:default", "default");
}

// The vendors' image files differ only where Embree's distances do: every hash of colour,
// normal, primID and geomID is the same in both, and both hold the same cases.
TEST(Golden, VendorImagesDifferOnlyInWhatFollowsFromTheRayDistance) {
  const auto amd = readGolden(imageGoldenFile("default", kVendors[0]));
  const auto intel = readGolden(imageGoldenFile("default", kVendors[1]));
  ASSERT_FALSE(amd.empty());
  ASSERT_EQ(amd.size(), intel.size());
  int distanceHashes = 0;
  for (const auto& [name, hash] : amd) {
    ASSERT_EQ(intel.count(name), 1u) << name;
    if (followsFromDistance(name))
      ++distanceHashes;
    else
      EXPECT_EQ(intel.at(name), hash) << name;
  }
  EXPECT_GT(distanceHashes, 0);
}

}  // namespace
