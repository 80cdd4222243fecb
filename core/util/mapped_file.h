#pragma once
// Read-only memory mapping of a whole file, used by the mesh loaders.
#include <cstddef>
#include <string>

namespace aperture {

/// Maps a regular file read-only. Throws Error for a missing, unreadable or non-regular path
/// (a directory, a device). An empty file maps to size() == 0 and data() == nullptr.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  const char* data() const { return data_; }
  size_t size() const { return size_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  const char* data_ = nullptr;
  size_t size_ = 0;
};

}  // namespace aperture

#include <charconv>
#include <cstdint>

namespace aperture {

/// Parses a whole token [b, e) as a double ("+" prefix, "nan" and "inf" accepted). False when
/// the token is not exactly one number.
inline bool parseDoubleToken(const char* b, const char* e, double& out) {
  if (b < e && *b == '+') ++b;
  if (b == e) return false;
  auto r = std::from_chars(b, e, out);
  return r.ec == std::errc() && r.ptr == e;
}

/// Parses a whole token [b, e) as a signed 64-bit integer ("+" prefix accepted).
inline bool parseIntToken(const char* b, const char* e, int64_t& out) {
  if (b < e && *b == '+') ++b;
  if (b == e) return false;
  auto r = std::from_chars(b, e, out);
  return r.ec == std::errc() && r.ptr == e;
}

/// A token for an error message: at most 40 characters, non-printable bytes as \xNN.
std::string printableToken(const char* b, const char* e);

}  // namespace aperture
