#include "file_errors.h"

#include <unistd.h>

#include <cerrno>
#include <filesystem>

#include "core/util/error.h"

namespace aperture::python {

namespace fs = std::filesystem;

void readingFiles(const std::vector<std::string>& paths, const std::function<void()>& read) {
  try {
    read();
  } catch (const Error& e) {
    for (const std::string& path : paths) {
      std::error_code ec;
      if (!fs::exists(path, ec)) throw FileError(ENOENT, e.what(), path);
      if (::access(path.c_str(), R_OK) != 0) throw FileError(errno, e.what(), path);
    }
    throw;
  }
}

void writingFile(const std::string& path, const std::function<void()>& write) {
  try {
    write();
  } catch (const Error& e) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw FileError(EISDIR, e.what(), path);
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    if (!fs::is_directory(dir, ec)) throw FileError(ENOENT, e.what(), path);
    if (::access(dir.c_str(), W_OK) != 0) throw FileError(errno, e.what(), path);
    throw;
  }
}

}  // namespace aperture::python
