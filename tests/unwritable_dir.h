#pragma once
// A directory in which no file can be created, for the tests of output checks.
#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>

namespace aperture::test {

/// Creates `path` as a directory no file can be created in: mode 0555, and for root (whom
/// modes do not stop) a read-only tmpfs mounted on it, unmounted again by the destructor.
/// ready() is false, with the reason in why(), where neither works (root without the right to
/// mount); tests then skip.
class UnwritableDir {
 public:
  explicit UnwritableDir(const std::string& path) : path_(path) {
    std::filesystem::create_directories(path);
    if (::geteuid() != 0) {
      ready_ = ::chmod(path.c_str(), 0555) == 0;
    } else {
      mounted_ = ::mount("tmpfs", path.c_str(), "tmpfs", MS_RDONLY, "size=64k") == 0;
      ready_ = mounted_;
    }
    if (!ready_) why_ = std::strerror(errno);
  }
  ~UnwritableDir() {
    if (mounted_) ::umount(path_.c_str());
    ::chmod(path_.c_str(), 0755);
  }
  UnwritableDir(const UnwritableDir&) = delete;
  UnwritableDir& operator=(const UnwritableDir&) = delete;

  bool ready() const { return ready_; }
  const std::string& why() const { return why_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_, why_;
  bool mounted_ = false, ready_ = false;
};

}  // namespace aperture::test

/// Declares `var`, an UnwritableDir at `path`, or skips the test with the reason.
#define APERTURE_REQUIRE_UNWRITABLE_DIR(var, path)                          \
  ::aperture::test::UnwritableDir var(path);                                \
  if (!var.ready())                                                         \
  GTEST_SKIP() << "cannot make an unwritable directory here (" << var.why() \
               << "): root needs the right to mount a read-only tmpfs"
