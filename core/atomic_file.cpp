#include "core/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>

#include "core/error.h"

namespace aperture {

namespace {

std::atomic<unsigned> temporaryCounter{0};

/// Splits "dir/name" into ("dir", "name"); a bare name lives in ".".
void splitPath(const std::string& path, std::string* dir, std::string* name) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) {
    *dir = ".";
    *name = path;
  } else {
    *dir = slash == 0 ? "/" : path.substr(0, slash);
    *name = path.substr(slash + 1);
  }
}

std::string errnoText(int err) { return std::strerror(err); }

/// Flushes the file at `path` to stable storage; returns 0 or an errno value.
int fsyncPath(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) return errno;
  int err = 0;
  if (::fsync(fd) != 0) err = errno;
  if (::close(fd) != 0 && err == 0) err = errno;
  return err;
}

}  // namespace

std::string temporaryPathFor(const std::string& finalPath, const std::string& suffix) {
  std::string dir, name;
  splitPath(finalPath, &dir, &name);
  const std::string prefix = finalPath.find('/') == std::string::npos ? "" : dir + "/";
  return cat(prefix, ".", name, ".tmp-", ::getpid(), "-", temporaryCounter.fetch_add(1), suffix);
}

void writeAtomically(const std::string& finalPath,
                     const std::function<void(const std::string& tmpPath)>& write,
                     const std::string& suffix) {
  std::string dir, name;
  splitPath(finalPath, &dir, &name);
  if (name.empty()) throw Error(cat("cannot write '", finalPath, "': not a file name"));
  struct stat st;
  if (::stat(dir.c_str(), &st) != 0)
    throw Error(cat("cannot write '", finalPath, "': directory '", dir, "': ", errnoText(errno)));
  if (!S_ISDIR(st.st_mode))
    throw Error(cat("cannot write '", finalPath, "': '", dir, "' is not a directory"));

  const std::string tmp = temporaryPathFor(finalPath, suffix);
  auto fail = [&](const std::string& reason) {
    std::remove(tmp.c_str());
    throw Error(cat("cannot write '", finalPath, "': ", reason));
  };
  try {
    write(tmp);
  } catch (const std::exception& e) {
    fail(e.what());
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (const int err = fsyncPath(tmp, O_RDONLY)) fail(cat("sync of ", tmp, ": ", errnoText(err)));
  if (::rename(tmp.c_str(), finalPath.c_str()) != 0) fail(cat("rename: ", errnoText(errno)));
  // Best effort: make the rename itself durable. The file is complete either way.
  fsyncPath(dir, O_RDONLY | O_DIRECTORY);
}

void writeTextAtomically(const std::string& finalPath, const std::string& text) {
  writeBytesAtomically(finalPath, text.data(), text.size());
}

void writeBytesAtomically(const std::string& finalPath, const void* data, size_t size) {
  const char* bytes = static_cast<const char*>(data);
  writeAtomically(finalPath, [&](const std::string& tmp) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(cat("create ", tmp, ": ", errnoText(errno)));
    size_t done = 0;
    while (done < size) {
      const ssize_t n = ::write(fd, bytes + done, size - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        const int err = errno;
        ::close(fd);
        throw Error(errnoText(err));
      }
      done += size_t(n);
    }
    if (::close(fd) != 0) throw Error(errnoText(errno));
  });
}

}  // namespace aperture
