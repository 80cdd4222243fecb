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

/// The items, each turned into text by `show`, joined by `separator`: the lists of messages
/// ("known: a, b, c") and headers.
template <typename Range, typename Show>
std::string join(const Range& items, const std::string& separator, Show show) {
  std::string s;
  bool first = true;
  for (const auto& item : items) {
    if (!first) s += separator;
    s += show(item);
    first = false;
  }
  return s;
}
/// The items (strings or C strings) joined by `separator`.
template <typename Range>
std::string join(const Range& items, const std::string& separator) {
  return join(items, separator, [](const auto& item) { return std::string(item); });
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
