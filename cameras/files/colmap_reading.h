#pragma once
// Reading COLMAP's files, text and binary: numbered lines and their tokens, numbers and ids
// parsed with the entry named in every error, and little-endian values read from a whole file,
// each checked against its end. The camera model reader (colmap_file.cpp) and the points
// reader (points_file.cpp) both read through these.
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "core/util/error.h"
#include "core/util/little_endian.h"

namespace aperture::camera_files {

/// The whole file; Error "PATH: cannot open the file" otherwise.
std::string readWholeFile(const std::string& path);

/// The file's lines, each with its number (1-based), trimmed of spaces, tabs and '\r'.
std::vector<std::pair<int, std::string>> textLines(const std::string& text);
/// What separates the tokens of a line: the C locale's white space.
inline constexpr const char* kTokenSeparators = " \t\n\v\f\r";
/// The tokens of a line, split at kTokenSeparators.
std::vector<std::string> tokensOf(const std::string& line);
/// The rest of `line` after its first `count` tokens and the separators after them ("" when
/// nothing follows): a last field that may hold separators, such as a COLMAP image's name.
std::string afterTokens(const std::string& line, size_t count);
/// Not empty and not a '#' comment.
bool isDataLine(const std::string& line);

/// `token` as a double; Error "CONTEXT: WHAT 'TOKEN' is not a number" otherwise.
double numberToken(const std::string& token, const std::string& context, const char* what);
/// `token` as an integer in [lo, hi]; Error naming `context`, `what` and the range otherwise.
long long integerToken(const std::string& token, const std::string& context, const char* what,
                       long long lo, long long hi);

/// COLMAP's image and camera ids are uint32.
inline constexpr long long kMaxColmapId = 0xffffffffll;

/// Reads little-endian values from a whole file, checking every read against its end; errors
/// name the file, what was read and the byte offset.
class BinaryReader {
 public:
  explicit BinaryReader(std::string path) : path_(std::move(path)), bytes_(readWholeFile(path_)) {}

  size_t remaining() const { return bytes_.size() - pos_; }
  size_t offset() const { return pos_; }
  const std::string& path() const { return path_; }

  template <typename T>
  T read(const std::string& what) {
    need(sizeof(T), what);
    const T value = loadLittleEndian<T>(bytes_.data() + pos_);
    pos_ += sizeof(T);
    return value;
  }

  /// A NUL-terminated string.
  std::string readName(const std::string& what);

  void skip(size_t n, const std::string& what) {
    need(n, what);
    pos_ += n;
  }

  /// A count read from the file, checked against what the rest of the file could hold at
  /// `minBytesEach` per entry, before anything is allocated from it.
  uint64_t readCount(size_t minBytesEach, const std::string& what);

 private:
  void need(size_t n, const std::string& what) const;

  std::string path_;
  std::string bytes_;
  size_t pos_ = 0;
};

}  // namespace aperture::camera_files
