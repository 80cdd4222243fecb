#include "tests/support.h"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/cli/camera_flags.h"
#include "core/util/error.h"

namespace fs = std::filesystem;

namespace aperture::test {

std::string sharedDir() { return APERTURE_SHARED_DIR; }

std::string sharedMesh(const std::string& relative) {
  fs::path p = fs::path(APERTURE_SHARED_DIR) / "meshes" / relative;
  return fs::exists(p) ? p.string() : std::string();
}

namespace {

/// This test process's folder of scratch directories, one per test.
fs::path processScratchRoot() {
  return fs::temp_directory_path() / ("aperture-test-" + std::to_string(::getpid()));
}

fs::path scratchDirOf(const ::testing::TestInfo* info) {
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "misc";
  for (char& c : name)
    if (c == '/') c = '_';
  return processScratchRoot() / name;
}

/// Removes a test's scratch directory when the test passes, and the process's folder when the
/// whole run passed; a failure keeps its files and names where they are.
class ScratchCleaner : public ::testing::EmptyTestEventListener {
  void OnTestEnd(const ::testing::TestInfo& info) override {
    const fs::path dir = scratchDirOf(&info);
    std::error_code ignored;
    if (info.result()->Passed())
      fs::remove_all(dir, ignored);
    else if (fs::exists(dir, ignored))
      std::fprintf(stderr, "scratch files of %s.%s kept in %s\n", info.test_suite_name(),
                   info.name(), dir.c_str());
  }
  void OnTestProgramEnd(const ::testing::UnitTest& unit) override {
    std::error_code ignored;
    if (unit.Passed()) fs::remove_all(processScratchRoot(), ignored);
  }
};

const bool kScratchCleanerInstalled = [] {
  ::testing::UnitTest::GetInstance()->listeners().Append(new ScratchCleaner);
  return true;
}();

}  // namespace

std::string scratchDir() {
  fs::path dir = scratchDirOf(::testing::UnitTest::GetInstance()->current_test_info());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string apertureBinary() { return APERTURE_BINARY; }

int runCommand(const std::string& command, std::string* output) {
  std::string full = command + " 2>&1";
  FILE* pipe = ::popen(full.c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buf;
  std::string out;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  int status = ::pclose(pipe);
  if (output) *output = out;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return -1;
}

Measured runMeasured(const std::string& command) {
  Measured m;
  int fds[2];
  if (::pipe(fds) != 0) return m;
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(fds[1], 1);
    ::dup2(fds[1], 2);
    ::close(fds[0]);
    ::close(fds[1]);
    const std::string line = "exec " + command;
    ::execl("/bin/sh", "sh", "-c", line.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(fds[1]);
  std::array<char, 4096> buf;
  ssize_t n;
  while ((n = ::read(fds[0], buf.data(), buf.size())) > 0) m.output.append(buf.data(), size_t(n));
  ::close(fds[0]);
  int status = 0;
  rusage usage{};
  if (::wait4(pid, &status, 0, &usage) != pid) return m;
  m.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  m.cpuSeconds = double(usage.ru_utime.tv_sec) + double(usage.ru_stime.tv_sec) +
                 1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  m.maxRssKb = usage.ru_maxrss;
  if (WIFEXITED(status)) m.exitCode = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) m.signal = WTERMSIG(status);
  return m;
}

void writeFile(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(bytes.data(), std::streamsize(bytes.size()));
}

bool fileExists(const std::string& path) { return fs::exists(path); }

namespace {
template <typename T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
}  // namespace

std::string differingAovs(const Framebuffer& a, const Framebuffer& b) {
  if (a.width != b.width || a.height != b.height || a.aovs != b.aovs)
    return "size or AOV set (" + std::to_string(a.width) + "x" + std::to_string(a.height) + " " +
           aovListString(a.aovs) + " vs " + std::to_string(b.width) + "x" +
           std::to_string(b.height) + " " + aovListString(b.aovs) + ")";
  std::string diff;
  auto check = [&](bool same, const char* name) {
    if (!same) diff += std::string(diff.empty() ? "" : ",") + name;
  };
  check(sameBits(a.rgba, b.rgba), "color");
  check(sameBits(a.depth, b.depth), "depth");
  check(sameBits(a.distance, b.distance), "distance");
  check(sameBits(a.normal, b.normal), "normal");
  check(sameBits(a.position, b.position), "position");
  check(sameBits(a.primId, b.primId), "primid");
  check(sameBits(a.geomId, b.geomId), "geomid");
  check(sameBits(a.shadingNormal, b.shadingNormal), "shading-normal");
  for (size_t k = 0; k < a.properties.size(); ++k)
    check(sameBits(a.properties[k].values, b.properties[k].values),
          a.properties[k].property.aovName().c_str());
  check(sameBits(a.layerDepth, b.layerDepth) && sameBits(a.layerDistance, b.layerDistance) &&
            sameBits(a.layerPrimId, b.layerPrimId) && sameBits(a.layerGeomId, b.layerGeomId),
        "layers");
  return diff;
}

void expectSameGeometry(const Framebuffer& a, const Framebuffer& b, int minHits) {
  ASSERT_EQ(a.pixelCount(), b.pixelCount());
  int hits = 0;
  for (size_t px = 0; px < a.pixelCount(); ++px) {
    ASSERT_EQ(a.geomId[px], b.geomId[px]) << "pixel " << px;
    if (a.geomId[px] == kInvalidId) continue;
    ++hits;
    EXPECT_NEAR(a.depth[px], b.depth[px], 1e-4 * b.depth[px]) << "pixel " << px;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(a.normal[3 * px + c], b.normal[3 * px + c], 1e-3) << "pixel " << px;
  }
  EXPECT_GE(hits, minHits);
}

std::string Fnv1a::hex() const {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", h_);
  return buf;
}

CameraParams cameraParamsFromFlags(const std::string& flags) {
  CLI::App app;
  app::CameraFlags camera;
  camera.add(app);
  app.parse(flags, false);
  return app::resolveCommandCamera(camera.given(), camera.defaults(), glm::dvec3(0.0),
                                   glm::dvec3(0.0));
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

int forEachHit(const Framebuffer& fb,
               const std::function<void(int, int, const Imath::V3d&, double, double)>& f) {
  int hits = 0;
  for (int i = 0; i < fb.height; ++i)
    for (int j = 0; j < fb.width; ++j) {
      const size_t px = size_t(i) * size_t(fb.width) + size_t(j);
      if (!std::isfinite(fb.depth[px])) continue;
      const float* p = &fb.position[3 * px];
      const double t = fb.distance.empty() ? std::nan("") : double(fb.distance[px]);
      f(i, j, Imath::V3d(p[0], p[1], p[2]), fb.depth[px], t);
      ++hits;
    }
  return hits;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace aperture::test
