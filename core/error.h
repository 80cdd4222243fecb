#pragma once
// Exceptions used throughout aperture: thrown with context, caught once in main.
#include <sstream>
#include <stdexcept>
#include <string>

namespace aperture {

/// A user-facing error: bad input, a file that cannot be read or written, a bad parameter.
/// The message names the file or flag and the offending value. main() exits with code 1.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

/// Builds a message from streamable parts: throw Error(cat("file ", path, ": bad count ", n)).
template <typename... Args>
std::string cat(const Args&... args) {
  std::ostringstream s;
  s.precision(17);
  (s << ... << args);
  return s.str();
}

}  // namespace aperture

/// Internal invariant check that prints both operands; active in every build type.
#define APERTURE_CHECK_OP(a, op, b)                                                           \
  do {                                                                                        \
    if (!((a)op(b)))                                                                          \
      throw ::aperture::Error(::aperture::cat(__FILE__, ":", __LINE__,                        \
                                              ": check failed: " #a " " #op " " #b " (", (a), \
                                              " vs ", (b), ")"));                             \
  } while (0)
