// End-to-end tests of the `aperture` executable: exit codes, messages, no partial outputs,
// bit-identical EXRs across packet widths and threads (EXR header reprojection:
// tests/core/exr/test_exr_header.cpp).
#include <gtest/gtest.h>
#include <sys/mount.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "core/exr/exr.h"
#include "tests/support.h"
#include "tests/unwritable_dir.h"

using namespace aperture;
using aperture::test::apertureBinary;
using aperture::test::quote;
using aperture::test::runCommand;
using aperture::test::scratchDir;

namespace {

const char* kBunnyView = " --eye -0.02,0.11,0.35 --at -0.017,0.11,0 --up 0,1,0 --fov 30";

TEST(Cli, HelpAndVersionExitZero) {
  std::string out;
  EXPECT_EQ(runCommand(apertureBinary() + " --help", &out), 0);
  EXPECT_NE(out.find("render"), std::string::npos);
  EXPECT_EQ(runCommand(apertureBinary() + " render --help", &out), 0);
  EXPECT_NE(out.find("--bvh-quality"), std::string::npos);
  EXPECT_EQ(runCommand(apertureBinary() + " frobnicate", &out), 2);
  EXPECT_NE(out.find("unknown command 'frobnicate'"), std::string::npos) << out;
  EXPECT_EQ(runCommand(apertureBinary() + " --version", &out), 0);
  EXPECT_NE(out.find("aperture"), std::string::npos);
}

TEST(Cli, DefaultSceneRendersExrAndPreview) {
  const std::string dir = scratchDir();
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() + " render --size 64,48 --out " + dir +
                           "/d.exr --preview " + dir + "/d.png",
                       &out),
            0)
      << out;
  const Framebuffer fb = readExr(dir + "/d.exr");
  EXPECT_EQ(fb.width, 64);
  EXPECT_EQ(fb.aovs, parseAovList("color,depth"));
  int hits = 0;
  for (size_t px = 0; px < fb.pixelCount(); ++px) hits += fb.rgba[4 * px + 3] > 0;
  EXPECT_GT(hits, 64 * 48 / 10) << "the default camera should see the default scene";
  EXPECT_TRUE(test::fileExists(dir + "/d.png"));
}

/// The shared libraries the dynamic loader loaded for `args` (LD_DEBUG=files), one line each.
std::string librariesLoadedBy(const std::string& args, const std::string& dir) {
  const std::string log = dir + "/ld";
  std::string out;
  EXPECT_EQ(runCommand("LD_DEBUG=files LD_DEBUG_OUTPUT=" + quote(log) + " " + apertureBinary() +
                           " " + args,
                       &out),
            0)
      << out;
  std::string loaded;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().filename().string().rfind("ld.", 0) == 0)
      loaded += test::readFile(entry.path().string());
  return loaded;
}

TEST(Cli, OpenImageIoLoadsOnlyForTheFilesThatNeedIt) {
  // OpenImageIO and its 261 libraries are a plugin (core/io/image_codec.h): a render to EXR never
  // loads it, a PNG preview does.
  const std::string exrOnly = scratchDir() + "/exr";
  const std::string withPng = scratchDir() + "/png";
  std::filesystem::create_directories(exrOnly);
  std::filesystem::create_directories(withPng);
  const std::string exrLog =
      librariesLoadedBy("render --size 64,48 --out " + quote(exrOnly + "/d.exr"), exrOnly);
  EXPECT_NE(exrLog.find("libembree3"), std::string::npos) << "the log names loaded libraries";
  EXPECT_EQ(exrLog.find("libOpenImageIO"), std::string::npos);
  EXPECT_EQ(exrLog.find("libaperture_oiio"), std::string::npos);
  const std::string pngLog =
      librariesLoadedBy("render --size 64,48 --out " + quote(withPng + "/d.exr") + " --preview " +
                            quote(withPng + "/d.png"),
                        withPng);
  EXPECT_NE(pngLog.find("libaperture_oiio"), std::string::npos);
  EXPECT_NE(pngLog.find("libOpenImageIO"), std::string::npos);
  EXPECT_TRUE(test::fileExists(withPng + "/d.png"));
}

TEST(Cli, AMissingImageCodecFailsBeforeTheMeshLoadsAndNamesTheFile) {
  const std::string dir = scratchDir();
  const std::string missing = dir + "/no-such-plugin.so";
  std::string out;
  EXPECT_EQ(runCommand("APERTURE_IMAGE_CODEC=" + quote(missing) + " " + apertureBinary() +
                           " render --size 64,48 --out " + quote(dir + "/d.exr") + " --preview " +
                           quote(dir + "/d.png"),
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("cannot load libaperture_oiio.so"), std::string::npos) << out;
  EXPECT_NE(out.find(missing + ": no such file"), std::string::npos) << out;
  EXPECT_EQ(out.find("loaded procedural"), std::string::npos) << "failed after loading: " << out;
  EXPECT_FALSE(test::fileExists(dir + "/d.exr"));
  EXPECT_FALSE(test::fileExists(dir + "/d.png"));
  // tradeoff compares images through the codec: it fails before its first render.
  EXPECT_EQ(runCommand("APERTURE_IMAGE_CODEC=" + quote(missing) + " " + apertureBinary() +
                           " tradeoff --size 32,24 --out-dir " + quote(dir + "/t"),
                       &out),
            1)
      << out;
  EXPECT_NE(out.find(missing + ": no such file"), std::string::npos) << out;
  EXPECT_FALSE(test::fileExists(dir + "/t"));
  // Without a file the codec writes, the variable is never read.
  EXPECT_EQ(runCommand("APERTURE_IMAGE_CODEC=" + quote(missing) + " " + apertureBinary() +
                           " render --size 64,48 --quiet --out " + quote(dir + "/d.exr"),
                       &out),
            0)
      << out;
}

TEST(Cli, BadFlagValuesNameTheFlagAndValueAndWriteNothing) {
  const std::string dir = scratchDir(), exr = dir + "/x.exr";
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--eye 1,2", "--eye"},
      {"--eye 0,0,5 --at 0,0,0 --up 0,0,1", "parallel"},
      {"--eye 0,0,5 --at 0,0,5", "look-at point equals the eye"},
      {"--up 0,0,0 --eye 1,1,1", "up vector is zero"},
      {"--fov 180 --eye 0,0,5", "--fov: 180: must be in (0, 180) degrees"},
      {"--d -1 --viewport 1,1 --eye 0,0,5", "--d: -1: must be > 0"},
      {"--d 1 --viewport 0,1 --eye 0,0,5", "viewport"},
      {"--size 0,10", "--size"},
      {"--size 100000,100000", "--size"},
      {"--aov color,bogus", "bogus"},
      {"--packet 3", "packet width 3"},
      {"--tile 30", "tile size 30"},
      {"--compression lzma", "lzma"},
      {"--bvh-quality ultra", "ultra"},
      {"--mesh /nonexistent/m.ply", "/nonexistent/m.ply"},
      {"--eye nan,0,1", "--eye: nan,0,1 is not finite"},
  };
  for (const Case& c : cases) {
    std::string out;
    const int rc = runCommand(apertureBinary() + " render --out " + exr + " " + c.args, &out);
    EXPECT_NE(rc, 0) << c.args;
    EXPECT_GT(rc, 0) << c.args << " (killed by a signal)";
    EXPECT_NE(out.find(c.expect), std::string::npos) << c.args << "\n" << out;
    EXPECT_FALSE(test::fileExists(exr)) << c.args;
  }
}

/// The budget of one malformed input: exit 1 or 2 (never a signal) with a message naming the
/// problem, no output, at most 2 s of CPU and 200 MB peak resident memory (the runtime alone,
/// Embree + TBB + OpenEXR mapped in, is ~10 MB; OpenImageIO, when a file loads it, adds
/// ~122 MB). Wall time is bounded at 10 s
/// by `timeout` and asserted under 5 s: on a loaded 2-core machine it is mostly waiting for a
/// core. Sanitized builds check exit codes and messages only (their shadow memory and
/// slowdown are not the product's).
void expectCleanFailure(const std::string& command, const std::string& name,
                        const std::vector<std::string>& expect, const std::string& output) {
  const test::Measured m = test::runMeasured("timeout 10 " + command);
  EXPECT_EQ(m.signal, 0) << name << " killed by signal " << m.signal << "\n" << m.output;
  EXPECT_TRUE(m.exitCode == 1 || m.exitCode == 2) << name << ": exit " << m.exitCode << "\n"
                                                  << m.output;
  for (const std::string& e : expect)
    EXPECT_NE(m.output.find(e), std::string::npos) << name << ": '" << e << "' in " << m.output;
  EXPECT_FALSE(test::fileExists(output)) << name;
#ifndef APERTURE_SANITIZED
  EXPECT_LT(m.cpuSeconds, 2.0) << name;
  EXPECT_LT(m.wallSeconds, 5.0) << name;
  EXPECT_LT(m.maxRssKb, 200 * 1024) << name;
#endif
  ::testing::Test::RecordProperty(name, std::to_string(m.cpuSeconds) + " s cpu, " +
                                            std::to_string(m.wallSeconds) + " s wall, " +
                                            std::to_string(m.maxRssKb / 1024) + " MB peak");
}

/// (file, expected message) pairs of a corpus directory's EXPECTED.txt.
std::vector<std::pair<std::string, std::string>> readManifest(const std::string& dir) {
  std::ifstream manifest(dir + "/EXPECTED.txt");
  std::vector<std::pair<std::string, std::string>> entries;
  std::string line;
  while (std::getline(manifest, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto tab = line.find('\t');
    entries.emplace_back(line.substr(0, tab), line.substr(tab + 1));
  }
  return entries;
}

}  // namespace

TEST(Cli, MalformedMeshCorpusFailsCleanlyWithoutOutput) {
  const std::string dir = scratchDir(), exr = dir + "/x.exr";
  const std::string bad = std::string(APERTURE_TESTS_DIR) + "/data/bad/";
  int files = 0;
  for (const auto& [name, expect] : readManifest(bad)) {
    const std::string command =
        apertureBinary() + " render --size 8,8 --out " + exr + " --mesh " + quote(bad + name);
    expectCleanFailure(command, name, {expect, name}, exr);  // the problem and the file
    ++files;
  }
  EXPECT_GE(files, 50);
  // An empty file and a directory, made here.
  test::writeFile(dir + "/empty.ply", "");
  std::string out;
  EXPECT_EQ(
      runCommand(apertureBinary() + " render --out " + exr + " --mesh " + dir + "/empty.ply", &out),
      1);
  EXPECT_NE(out.find("empty.ply"), std::string::npos) << out;
  std::filesystem::create_directories(dir + "/adir.ply");
  EXPECT_EQ(
      runCommand(apertureBinary() + " render --out " + exr + " --mesh " + dir + "/adir.ply", &out),
      1);
  EXPECT_NE(out.find("directory"), std::string::npos) << out;
  EXPECT_FALSE(test::fileExists(exr));
}

TEST(Cli, MalformedJobCorpusFailsCleanlyWithoutOutput) {
  // Copied beside a copy of the mesh corpus, so the jobs' relative paths (../bad/...) resolve
  // and nothing they might write lands in the source tree.
  const std::string dir = scratchDir();
  namespace fs = std::filesystem;
  const std::string data = std::string(APERTURE_TESTS_DIR) + "/data/";
  fs::copy(data + "bad_jobs", dir + "/bad_jobs");
  fs::copy(data + "bad", dir + "/bad");
  int files = 0;
  for (const auto& [name, expect] : readManifest(dir + "/bad_jobs")) {
    const std::string job = dir + "/bad_jobs/" + name;
    expectCleanFailure(apertureBinary() + " batch --quiet " + quote(job), name, {expect},
                       dir + "/bad_jobs/out");
    ++files;
  }
  EXPECT_GE(files, 25);
  EXPECT_FALSE(fs::exists(dir + "/bad_jobs/summary.json"));
}

TEST(Cli, PacketWidthsAndThreadsGiveBitIdenticalExrOnBunny) {
  APERTURE_REQUIRE_SHARED_MESH(bunny, "stanford/bun_zipper.ply");
  const std::string dir = scratchDir();
  Framebuffer ref;
  for (int packet : {1, 4, 8, 16})
    for (int threads : {1, 2}) {
      const std::string exr =
          dir + "/p" + std::to_string(packet) + "t" + std::to_string(threads) + ".exr";
      std::string out;
      ASSERT_EQ(runCommand(apertureBinary() + " render --quiet --mesh " + bunny + kBunnyView +
                               " --size 203,157 --aov all --packet " + std::to_string(packet) +
                               " --threads " + std::to_string(threads) + " --tile " +
                               std::to_string(8 * packet) + " --out " + exr,
                           &out),
                0)
          << out;
      const Framebuffer fb = readExr(exr);
      if (ref.width == 0) {
        ref = fb;
        int hits = 0;
        for (uint32_t id : fb.primId) hits += id != kInvalidId;
        EXPECT_GT(hits, 203 * 157 / 4);
      } else {
        EXPECT_EQ(test::differingAovs(fb, ref), "")
            << "packet " << packet << " threads " << threads;
      }
    }
}

TEST(Cli, PacketWidthsGiveBitIdenticalPrimIdsOnTheCrown) {
  // The crown has coincident triangles: every width must break their ties the same way.
  APERTURE_REQUIRE_SHARED_MESH(crown, "scenes/crown_flat.ply");
  const std::string dir = scratchDir();
  Framebuffer ref;
  for (int packet : {16, 1, 4, 8}) {
    const std::string exr = dir + "/p" + std::to_string(packet) + ".exr";
    std::string out;
    ASSERT_EQ(runCommand(apertureBinary() + " render --quiet --mesh " + crown +
                             " --eye 0,5.5,24 --at 0,11,-10 --fov 47 --fov-axis x --size 250,350"
                             " --aov primid,depth,normal --packet " +
                             std::to_string(packet) + " --out " + exr,
                         &out),
              0)
        << out;
    const Framebuffer fb = readExr(exr);
    if (packet == 16)
      ref = fb;
    else
      EXPECT_EQ(test::differingAovs(fb, ref), "") << "packet " << packet;
  }
}

TEST(Cli, BenchReportsRenderAndBaselineInJson) {
  const std::string jsonPath = scratchDir() + "/b.json";
  std::string out;
  ASSERT_EQ(runCommand(apertureBinary() +
                           " bench --quiet --size 64,64 --frames 3 --warmup 1 --builds 2 "
                           "--baseline --mesh 'procedural:sphere' --json " +
                           jsonPath,
                       &out),
            0)
      << out;
  const std::string text = test::readFile(jsonPath);
  for (const char* key : {"\"mrays_per_s_median\"", "\"baseline_mrays_per_s_median\"",
                          "\"build_seconds_median\"", "\"embree_bytes_per_triangle\"", "\"isa\""})
    EXPECT_NE(text.find(key), std::string::npos) << key;
  EXPECT_NE(out.find("render / baseline"), std::string::npos) << out;
}

TEST(Cli, BenchBaselineStreamApisTraceTheSameRays) {
  // Every Embree API of the baseline traces every pixel: the same ray count in the JSON
  // (no lane lost or doubled in the stream layouts). The count is the image's pixel count.
  for (const char* api : {"packet16", "stream-nm", "stream-1m"}) {
    const std::string jsonPath = scratchDir() + "/b_" + api + ".json";
    std::string out;
    ASSERT_EQ(runCommand(apertureBinary() +
                             " bench --quiet --size 61,45 --frames 1 --warmup 0 --builds 1 "
                             "--baseline --mesh 'procedural:sphere' --baseline-api " +
                             api + " --json " + jsonPath,
                         &out),
              0)
        << out;
    const nlohmann::json j = test::readJson(jsonPath);
    EXPECT_EQ(j["baseline_api"], api);
    EXPECT_EQ(j["baseline_rays_per_frame"], 61 * 45) << api;
  }
  std::string out;
  EXPECT_NE(
      runCommand(apertureBinary() + " bench --baseline --baseline-api stream --size 8,8", &out), 0);
  EXPECT_NE(out.find("--baseline-api: 'stream' is not"), std::string::npos) << out;
}

TEST(Cli, CameraDescribePrintsFrameConventionsAndVolume) {
  std::string out;
  // Horizontal fov 47° on a 1000x1400 image: vertical fov 2·atan(tan(23.5°)·1.4) = 62.6609°.
  ASSERT_EQ(
      runCommand(apertureBinary() + " camera --describe --eye 0,5.5,24 --at 0,11,-10 "
                                    "--fov 47 --fov-axis x --size 1000,1400 --near 1 --far 100",
                 &out),
      0)
      << out;
  for (const char* text :
       {"e = (0, 5.5, 24)", "fov horizontal 47 deg", "vertical 62.6608", "frustum", "far top-left"})
    EXPECT_NE(out.find(text), std::string::npos) << text << "\n" << out;
  EXPECT_NE(
      runCommand(apertureBinary() + " camera --describe --eye 0,0,1 --at 0,0,0 --up 0,0,1", &out),
      0);
  EXPECT_NE(out.find("parallel"), std::string::npos) << out;
}

namespace {

// Issue 10 item 2: refused before any work, non-zero exit, every named flag in the message,
// and no file written (neither the EXR nor the preview).
TEST(Cli, RefusedCameraParametersNameTheFlagsAndWriteNothing) {
  const std::string dir = scratchDir(), exr = dir + "/x.exr", png = dir + "/x.png";
  struct Case {
    std::string args;
    std::vector<std::string> expect;
  } cases[] = {
      {"--fov 0", {"--fov: 0: must be in (0, 180) degrees"}},
      {"--fov 180", {"--fov: 180: must be in (0, 180)"}},
      {"--fov 200", {"--fov: 200"}},
      {"--fov 30 --focal-length 50", {"--fov", "--focal-length", "conflict"}},
      {"--fov 30 --viewport 1,1", {"--fov", "--viewport", "conflict"}},
      {"--focal-length 35 --viewport 1,1", {"--focal-length", "--viewport", "conflict"}},
      {"--eye 0,0,5 --at 0,0,0 --dir 0,0,-1", {"--at", "--dir", "conflict"}},
      {"--camera oblique --viewport 1,1 --oblique-dir 0,0,-1 --oblique-angles 1,1",
       {"--oblique-dir", "--oblique-angles", "conflict"}},
      {"--d 2", {"--d", "--viewport"}},
      {"--sensor 24,36", {"--sensor", "--focal-length"}},
      {"--fisheye-fov 200", {"--fisheye-fov", "does not apply to a 'perspective'"}},
      {"--camera thinlens --aperture -1", {"--aperture: -1: must be >= 0"}},
      {"--camera fisheye --fisheye-fov 0", {"--fisheye-fov: 0: must be in (0, 360]"}},
      {"--camera pinhole", {"--camera", "unknown camera type 'pinhole'"}},
      {"--size 640x480x3", {"--size"}},
      {"--spp 0", {"--spp: 0"}},
  };
  for (const Case& c : cases) {
    std::string out;
    const int rc =
        runCommand(apertureBinary() + " render --mesh 'procedural:spheres?tris=200000000' --out " +
                       exr + " --preview " + png + " " + c.args,
                   &out);
    EXPECT_TRUE(rc == 1 || rc == 2) << c.args << ": exit " << rc << "\n" << out;
    for (const std::string& e : c.expect)
      EXPECT_NE(out.find(e), std::string::npos) << c.args << ": no '" << e << "' in\n" << out;
    EXPECT_EQ(out.find("loaded"), std::string::npos) << c.args << ": refused after loading";
    EXPECT_FALSE(test::fileExists(exr)) << c.args;
    EXPECT_FALSE(test::fileExists(png)) << c.args;
  }
}

TEST(Cli, UnknownFlagsAndCommandsGetDidYouMean) {
  std::string out;
  EXPECT_EQ(runCommand(apertureBinary() + " render --fvo 30", &out), 2);
  EXPECT_NE(out.find("unknown flag '--fvo' for 'render' (did you mean '--fov'?)"),
            std::string::npos)
      << out;
  EXPECT_EQ(runCommand(apertureBinary() + " bench --focal-lenght 35", &out), 2);
  EXPECT_NE(out.find("did you mean '--focal-length'?"), std::string::npos) << out;
  EXPECT_EQ(runCommand(apertureBinary() + " rendr", &out), 2);
  EXPECT_NE(out.find("did you mean 'render'?"), std::string::npos) << out;
  EXPECT_EQ(runCommand(apertureBinary() + " render --camera fishey", &out), 1);
  EXPECT_NE(out.find("did you mean 'fisheye'?"), std::string::npos) << out;
}

TEST(Cli, SizeAcceptsWxH) {
  const std::string exr = scratchDir() + "/x.exr";
  std::string out;
  ASSERT_EQ(
      runCommand(apertureBinary() + " render --quiet --size 64x48 --aov depth --out " + exr, &out),
      0)
      << out;
  const Framebuffer fb = readExr(exr);
  EXPECT_EQ(fb.width, 64);
  EXPECT_EQ(fb.height, 48);
}

}  // namespace

namespace {

/// Every file under `dir`, recursively, with its size (what "wrote nothing" compares).
std::vector<std::pair<std::string, uintmax_t>> listing(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, uintmax_t>> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    files.emplace_back(fs::relative(e.path(), dir).string(), e.is_directory() ? 0 : e.file_size());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

// Issue 10 item 5: output and preview paths, their directories, their extensions, the AOVs a
// preview needs and --preview-range are refused before the mesh is loaded (the mesh here would
// take minutes), naming the flag and the value, and nothing at all is written.
TEST(Cli, RefusedOutputsNameTheFlagAndValueAndWriteNothing) {
  const std::string dir = scratchDir(), exr = dir + "/x.exr", png = dir + "/x.png";
  std::filesystem::create_directories(dir + "/adir");
  test::writeFile(dir + "/afile", "a regular file");
  APERTURE_REQUIRE_UNWRITABLE_DIR(ro, dir + "/ro");
  const auto before = listing(dir);
  struct Case {
    std::string args;
    std::vector<std::string> expect;
  } cases[] = {
      {"--out " + dir + "/x.jpg", {"--out: '" + dir + "/x.jpg'", "supported: .exr"}},
      {"--out " + dir + "/x.png", {"--out: '" + dir + "/x.png'", "holds one AOV"}},
      {"--out " + dir + "/adir", {"--out: '" + dir + "/adir': is a directory"}},
      {"--out " + dir + "/adir/", {"--out: '" + dir + "/adir/': is a directory"}},
      {"--out " + ro.path() + "/x.exr", {"--out: '" + ro.path() + "/x.exr'", "not writable"}},
      {"--out " + exr + " --preview " + dir + "/adir",
       {"--preview: '" + dir + "/adir': is a directory"}},
      {"--out " + exr + " --preview " + dir + "/p.gif",
       {"--preview: '" + dir + "/p.gif': unknown extension '.gif'", ".png .jpg"}},
      {"--out " + exr + " --preview " + dir + "/p",
       {"--preview: '" + dir + "/p': has no extension"}},
      {"--out " + exr + " --preview " + dir + "/afile/sub/p.png",
       {"--preview: '" + dir + "/afile/sub/p.png': cannot create directory", "not a directory"}},
      {"--out " + exr + " --preview " + ro.path() + "/p.png",
       {"--preview: '" + ro.path() + "/p.png': directory '" + ro.path() + "' is not writable"}},
      {"--out " + exr + " --preview " + png + " --aov position,distance",
       {"--preview: '" + png + "': none of the AOVs distance,position can be previewed"}},
      {"--out " + exr + " --preview " + png + " --preview-range 5,2",
       {"--preview-range: '5,2': NEAR 5 must be less than FAR 2"}},
      {"--out " + exr + " --preview " + png + " --preview-range -1,2",
       {"--preview-range: '-1,2': NEAR -1 must be >= 0"}},
      {"--out " + exr + " --preview " + png + " --preview-range 1,inf",
       {"--preview-range: '1,inf'", "non-finite"}},
      {"--out " + exr + " --preview " + png + " --preview-range 4", {"--preview-range", "'4'"}},
      {"--out " + exr + " --preview-range 1,2", {"--preview-range: '1,2' needs --preview"}},
  };
  for (const Case& c : cases) {
    std::string out;
    const int rc =
        runCommand(apertureBinary() +
                       " render --mesh 'procedural:spheres?tris=200000000' --size 8,8 " + c.args,
                   &out);
    EXPECT_EQ(rc, 1) << c.args << "\n" << out;
    for (const std::string& e : c.expect)
      EXPECT_NE(out.find(e), std::string::npos) << c.args << ": no '" << e << "' in\n" << out;
    EXPECT_EQ(out.find("loaded"), std::string::npos) << c.args << ": refused after loading";
    EXPECT_EQ(listing(dir), before) << c.args << ": wrote a file";
  }
}

// A preview that fails while it is written (here: its 64 KB file system is full) fails the
// render, and the EXR, written after it, does not exist.
TEST(Cli, APreviewThatFailsWhileWritingLeavesNoExr) {
  const std::string dir = scratchDir(), small = dir + "/small";
  std::filesystem::create_directories(small);
  if (::mount("tmpfs", small.c_str(), "tmpfs", 0, "size=64k") != 0)
    GTEST_SKIP() << "cannot mount a 64 KB tmpfs here (" << std::strerror(errno) << ")";
  struct Unmount {
    std::string dir;
    ~Unmount() { ::umount(dir.c_str()); }
  } unmount{small};
  std::string out;
  // An uncompressed 256x256 BMP is 192 KB: it cannot fit.
  const int rc = runCommand(apertureBinary() + " render --quiet --mesh procedural:cube --size " +
                                "256,256 --eye 2,2,2 --at 0,0,0 --out " + dir + "/x.exr " +
                                "--preview " + small + "/p.bmp",
                            &out);
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("cannot write '" + small + "/p.bmp'"), std::string::npos) << out;
  EXPECT_FALSE(test::fileExists(dir + "/x.exr")) << "the EXR of a failed preview was written";
  EXPECT_TRUE(listing(small).empty()) << "a temporary file remains";
  // The same render with room for the preview writes both.
  ASSERT_EQ(runCommand(apertureBinary() + " render --quiet --mesh procedural:cube --size " +
                           "256,256 --eye 2,2,2 --at 0,0,0 --out " + dir + "/x.exr " +
                           "--preview " + dir + "/p.bmp",
                       &out),
            0)
      << out;
  EXPECT_TRUE(isCompleteExr(dir + "/x.exr"));
}
