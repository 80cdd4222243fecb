#include "core/io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <set>

#include "core/util/error.h"

namespace aperture {

namespace {

std::atomic<unsigned> temporaryCounter{0};

/// Between NAME and PID in a temporary name.
constexpr const char* kTemporaryMarker = ".tmp-";

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

/// Reads the decimal digits of `text` from `pos` up to `end` into *value; false unless there
/// is at least one digit and nothing else (and at most 18 digits, so it fits).
bool parseDigits(const std::string& text, size_t pos, size_t end, unsigned long long* value) {
  if (pos >= end || end - pos > 18) return false;
  *value = 0;
  for (size_t k = pos; k < end; ++k) {
    if (text[k] < '0' || text[k] > '9') return false;
    *value = *value * 10 + unsigned(text[k] - '0');
  }
  return true;
}

/// Parses "PID-N" + suffix starting at `pos` of `fileName`.
bool parsePidCounterSuffix(const std::string& fileName, size_t pos, TemporaryName* out) {
  const size_t dash = fileName.find('-', pos);
  if (dash == std::string::npos) return false;
  size_t end = dash + 1;
  while (end < fileName.size() && fileName[end] >= '0' && fileName[end] <= '9') ++end;
  unsigned long long pid = 0, counter = 0;
  if (!parseDigits(fileName, pos, dash, &pid) || !parseDigits(fileName, dash + 1, end, &counter))
    return false;
  if (end < fileName.size() && fileName[end] != '.') return false;
  out->pid = long(pid);
  out->counter = static_cast<unsigned long>(counter);
  out->suffix = fileName.substr(end);
  return true;
}

}  // namespace

std::optional<TemporaryName> parseTemporaryName(const std::string& fileName) {
  if (fileName.size() < 2 || fileName[0] != '.' || fileName.find('/') != std::string::npos)
    return std::nullopt;
  const std::string marker = kTemporaryMarker;
  // NAME may itself contain the marker, so try every occurrence, the last first.
  for (size_t at = fileName.rfind(marker); at != std::string::npos && at > 1;
       at = fileName.rfind(marker, at - 1)) {
    TemporaryName name;
    if (!parsePidCounterSuffix(fileName, at + marker.size(), &name)) continue;
    name.finalName = fileName.substr(1, at - 1);
    return name;
  }
  return std::nullopt;
}

std::string temporaryPathFor(const std::string& finalPath, const std::string& suffix) {
  std::string dir, name;
  splitPath(finalPath, &dir, &name);
  const std::string prefix = finalPath.find('/') == std::string::npos ? "" : dir + "/";
  const long pid = long(::getpid());
  const unsigned long counter = temporaryCounter.fetch_add(1);
  const std::string tmpName = cat(".", name, kTemporaryMarker, pid, "-", counter, suffix);
  const std::optional<TemporaryName> back = parseTemporaryName(tmpName);
  if (!back || back->finalName != name || back->pid != pid || back->counter != counter ||
      back->suffix != suffix)
    throw Error(cat("cannot write '", finalPath, "': temporary name '", tmpName,
                    "' does not parse back (suffix '", suffix,
                    "' must be empty or start with '.')"));
  return prefix + tmpName;
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
  writePiecesAtomically(finalPath, {{data, size}});
}

void writePiecesAtomically(const std::string& finalPath, const std::vector<BytePiece>& pieces) {
  writeAtomically(finalPath, [&](const std::string& tmp) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(cat("create ", tmp, ": ", errnoText(errno)));
    for (const BytePiece& piece : pieces) {
      const char* bytes = static_cast<const char*>(piece.data);
      size_t done = 0;
      while (done < piece.size) {
        const ssize_t n = ::write(fd, bytes + done, piece.size - done);
        if (n < 0) {
          if (errno == EINTR) continue;
          const int err = errno;
          ::close(fd);
          throw Error(errnoText(err));
        }
        done += size_t(n);
      }
    }
    if (::close(fd) != 0) throw Error(errnoText(errno));
  });
}

bool processAlive(long pid) {
  if (pid <= 0 || pid > long(INT_MAX)) return false;
  return !(::kill(pid_t(pid), 0) == -1 && errno == ESRCH);
}

std::vector<TemporaryFile> findTemporaries(const std::vector<std::string>& finalPaths,
                                           const std::function<bool(long)>& alive) {
  std::map<std::string, std::set<std::string>> namesByDirectory;
  for (const std::string& path : finalPaths) {
    const std::filesystem::path p(path);
    namesByDirectory[p.parent_path().empty() ? "." : p.parent_path().string()].insert(
        p.filename().string());
  }
  std::vector<TemporaryFile> found;
  for (const auto& [directory, names] : namesByDirectory) {
    std::error_code ec;
    for (std::filesystem::directory_iterator it(directory, ec), end; !ec && it != end;
         it.increment(ec)) {
      const std::optional<TemporaryName> t = parseTemporaryName(it->path().filename().string());
      if (t && names.count(t->finalName))
        found.push_back({it->path().string(), t->pid, alive(t->pid)});
    }
  }
  std::sort(found.begin(), found.end(),
            [](const TemporaryFile& a, const TemporaryFile& b) { return a.path < b.path; });
  return found;
}
}  // namespace aperture
