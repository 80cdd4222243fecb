#pragma once
// Which failures are Python OSErrors: a file that is missing, unreadable or cannot be written.
// The C++ libraries throw aperture::Error for every failure (bad values and files alike); the
// bindings re-classify an Error as a FileError by looking at the path afterwards, so the
// message stays the command line's.
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace aperture::python {

/// An Error about a file; raised in Python as FileNotFoundError, PermissionError or OSError
/// by errno, with the C++ message and the path.
class FileError : public std::runtime_error {
 public:
  FileError(int errnum, const std::string& what, std::string path)
      : std::runtime_error(what), errnum_(errnum), path_(std::move(path)) {}
  int errnum() const { return errnum_; }
  const std::string& path() const { return path_; }

 private:
  int errnum_;
  std::string path_;
};

/// Runs `read`; an Error it throws becomes a FileError when one of `paths` does not exist or
/// cannot be read (ENOENT, EACCES), and stays an Error otherwise (a bad value inside a file).
void readingFiles(const std::vector<std::string>& paths, const std::function<void()>& read);

/// Runs `write`; an Error it throws becomes a FileError when the directory of `path` does not
/// exist or is not writable, or `path` is a directory.
void writingFile(const std::string& path, const std::function<void()>& write);

}  // namespace aperture::python
