// Output safety of the real `aperture` binary: a full disk (file-size limit, or a 1 MB tmpfs
// where mounting is permitted) and SIGKILL in the middle of writing never leave a partial EXR
// under the final name, and the previous file survives.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "core/exr/exr.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;
using test::apertureBinary;
using test::runCommand;
using test::scratchDir;

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Names in `dir` other than `keep`: leftovers such as ".x.exr.tmp-PID-N".
std::vector<std::string> othersIn(const std::string& dir, const std::string& keep) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename() != keep) names.push_back(e.path().filename().string());
  return names;
}

/// A small, complete previous file under `exr`.
std::string renderPrevious(const std::string& exr) {
  std::string out;
  EXPECT_EQ(runCommand(apertureBinary() + " render --quiet --size 16,16 --out " + exr, &out), 0)
      << out;
  return readBytes(exr);
}

// 512x512, every AOV, no compression: about 15 MB, far past the limits below.
const char* kLargeRender = " render --quiet --size 512,512 --aov all --compression none";

TEST(OutputSafety, FileSizeLimitIsACleanErrorAndKeepsThePreviousFile) {
  const std::string dir = scratchDir(), exr = dir + "/x.exr";
  const std::string before = renderPrevious(exr);
  ASSERT_FALSE(before.empty());
  std::string out;
  // ulimit -f counts 1024-byte blocks: files may not grow past 256 KB.
  const int rc =
      runCommand("ulimit -f 256; exec " + apertureBinary() + kLargeRender + " --out " + exr, &out);
  EXPECT_EQ(rc, 1) << "exit code (not a signal such as SIGXFSZ): " << out;
  EXPECT_NE(out.find("cannot write '" + exr + "'"), std::string::npos) << out;
  EXPECT_NE(out.find(std::strerror(EFBIG)), std::string::npos) << out;
  EXPECT_EQ(readBytes(exr), before) << "the previous file must be intact";
  EXPECT_TRUE(othersIn(dir, "x.exr").empty()) << "a temporary file was left behind";

  // The bench summary JSON and the PNG preview go through the same path.
  const std::string jsonPath = dir + "/b.json";
  test::writeFile(jsonPath, "{\"previous\": true}\n");
  EXPECT_EQ(runCommand("ulimit -f 0; exec " + apertureBinary() +
                           " bench --quiet --size 16,16 --frames 1 --warmup 0 --builds 1 --json " +
                           jsonPath,
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("cannot write '" + jsonPath + "'"), std::string::npos) << out;
  EXPECT_EQ(readBytes(jsonPath), "{\"previous\": true}\n");
  EXPECT_EQ(othersIn(dir, "x.exr"), std::vector<std::string>{"b.json"});
}

TEST(OutputSafety, SmallFilesystemIsACleanErrorAndKeepsThePreviousFile) {
  const std::string dir = scratchDir() + "/tiny";
  fs::create_directories(dir);
  if (::mount("tmpfs", dir.c_str(), "tmpfs", 0, "size=1m") != 0)
    GTEST_SKIP() << "cannot mount a 1 MB tmpfs here (" << std::strerror(errno)
                 << "; needs root with CAP_SYS_ADMIN); the file-size-limit test covers ENOSPC's "
                    "sibling EFBIG";
  struct Unmount {
    std::string dir;
    ~Unmount() { ::umount(dir.c_str()); }
  } unmount{dir};
  const std::string exr = dir + "/x.exr";
  const std::string before = renderPrevious(exr);
  ASSERT_FALSE(before.empty());
  std::string out;
  EXPECT_EQ(runCommand(apertureBinary() + kLargeRender + " --out " + exr, &out), 1) << out;
  EXPECT_NE(out.find(std::strerror(ENOSPC)), std::string::npos) << out;
  EXPECT_EQ(readBytes(exr), before);
  EXPECT_TRUE(othersIn(dir, "x.exr").empty());
}

/// Starts `aperture` with `args` (stdout and stderr to /dev/null); returns its pid.
pid_t spawn(const std::vector<std::string>& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

/// Whether `dir` holds a temporary file of `name` (".name.tmp-...") with some bytes in it.
bool writingInProgress(const std::string& dir, const std::string& name) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string f = e.path().filename().string();
    if (f.rfind("." + name + ".tmp-", 0) == 0 && e.file_size(ec) > 0) return true;
  }
  return false;
}

TEST(OutputSafety, SigkillDuringTheWriteLeavesThePreviousOrACompleteFile) {
  const std::string dir = scratchDir(), exr = dir + "/x.exr";
  const std::string before = renderPrevious(exr);
  ASSERT_TRUE(isCompleteExr(exr));
  // 1024x1024, every AOV, uncompressed: ~59 MB, so the write takes a while.
  const std::vector<std::string> args = {apertureBinary(), "render", "--quiet", "--size",
                                         "1024,1024",      "--aov",  "all",     "--compression",
                                         "none",           "--out",  exr};
  std::mt19937 rng(12345);
  int killedMidWrite = 0;
  for (int round = 0; round < 6; ++round) {
    const pid_t pid = spawn(args);
    ASSERT_GT(pid, 0);
    // Wait for the temporary file to start filling, then kill after 0-20 ms.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    bool seen = false;
    int status = 0;
    bool exited = false;
    while (std::chrono::steady_clock::now() < deadline) {
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        exited = true;
        break;
      }
      if (writingInProgress(dir, "x.exr")) {
        seen = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    if (!exited) {
      std::this_thread::sleep_for(std::chrono::milliseconds(rng() % 21));
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      if (seen && WIFSIGNALED(status)) ++killedMidWrite;
    }
    // The final name holds the previous file byte for byte, or a complete new one.
    const std::string now = readBytes(exr);
    if (now != before) {
      EXPECT_TRUE(isCompleteExr(exr))
          << "round " << round << ": a partial EXR under the final name";
      const Framebuffer fb = readExr(exr);
      EXPECT_EQ(fb.width, 1024);
    }
    // Start each round from the small previous file; remove the dead process's temporary.
    for (const std::string& f : othersIn(dir, "x.exr")) fs::remove(dir + "/" + f);
    test::writeFile(exr, before);
  }
  EXPECT_GE(killedMidWrite, 3) << "the kills did not land during the write often enough";
}

}  // namespace
}  // namespace aperture
