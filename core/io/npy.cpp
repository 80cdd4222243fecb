// The NumPy .npy header (NumPy's "format.rst", versions 1.0 to 3.0):
//
//   magic "\x93NUMPY", major and minor version bytes, the header length (little-endian uint16
//   in 1.0, uint32 in 2.0 and 3.0), then the header: a Python dict literal with the keys
//   'descr' (the dtype string), 'fortran_order' (True / False) and 'shape' (a tuple of
//   integers), padded with spaces and ended by '\n' so the data starts at a multiple of 64
//   bytes. Version 3.0 differs from 2.0 only in allowing UTF-8 in the dict.
//
// Written: always 1.0, the dict in NumPy's own key order. Read: the three keys in any order,
// single or double quotes, a trailing comma or none; any other key or a structured dtype (a
// list as 'descr') is refused.
#include "core/io/npy.h"

#include <cctype>
#include <cstring>

#include "core/util/error.h"
#include "core/util/little_endian.h"

namespace aperture {

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr size_t kMagicBytes = 6;
/// The data starts at a multiple of this (NumPy's ARRAY_ALIGN).
constexpr size_t kAlignment = 64;

std::string shapeText(const std::vector<uint64_t>& shape) {
  if (shape.size() == 1) return cat("(", shape[0], ",)");
  return cat("(", join(shape, ", ", [](uint64_t d) { return std::to_string(d); }), ")");
}

/// Reads the dict literal of a header; every error names `what`.
class DictParser {
 public:
  DictParser(const std::string& text, const std::string& what) : text_(text), what_(what) {}

  NpyHeader parse() {
    NpyHeader h;
    bool haveDescr = false, haveOrder = false, haveShape = false;
    expect('{');
    while (!peek('}')) {
      const std::string key = quoted("a key");
      expect(':');
      if (key == "descr") {
        if (peek('[')) fail("a structured dtype (a list as 'descr') is not supported");
        h.descr = quoted("the 'descr' value");
        haveDescr = true;
      } else if (key == "fortran_order") {
        h.fortranOrder = boolean();
        haveOrder = true;
      } else if (key == "shape") {
        h.shape = tuple();
        haveShape = true;
      } else {
        fail(cat("unknown key '", key, "'"));
      }
      if (!peek('}')) expect(',');
    }
    expect('}');
    skipSpaces();
    if (pos_ != text_.size()) fail("text after the closing '}'");
    if (!haveDescr || !haveOrder || !haveShape)
      fail(cat("the header lacks '",
               !haveDescr   ? "descr"
               : !haveOrder ? "fortran_order"
                            : "shape",
               "'"));
    return h;
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw Error(cat(what_, ": bad NPY header ", why, " (header '", text_, "')"));
  }

  void skipSpaces() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }

  bool peek(char c) {
    skipSpaces();
    return pos_ < text_.size() && text_[pos_] == c;
  }

  void expect(char c) {
    if (!peek(c)) fail(cat("expected '", c, "' at byte ", pos_));
    ++pos_;
  }

  std::string quoted(const char* what) {
    skipSpaces();
    if (pos_ >= text_.size() || (text_[pos_] != '\'' && text_[pos_] != '"'))
      fail(cat("expected ", what, " in quotes at byte ", pos_));
    const char quote = text_[pos_++];
    const size_t end = text_.find(quote, pos_);
    if (end == std::string::npos) fail(cat(what, " has no closing quote"));
    std::string s = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return s;
  }

  bool boolean() {
    skipSpaces();
    for (const auto& [word, value] : {std::pair{"True", true}, std::pair{"False", false}})
      if (text_.compare(pos_, std::strlen(word), word) == 0) {
        pos_ += std::strlen(word);
        return value;
      }
    fail(cat("'fortran_order' is not True or False at byte ", pos_));
  }

  std::vector<uint64_t> tuple() {
    std::vector<uint64_t> dims;
    expect('(');
    while (!peek(')')) {
      const size_t start = pos_;
      uint64_t d = 0;
      while (pos_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[pos_]))) {
        const uint64_t digit = uint64_t(text_[pos_] - '0');
        if (d > (UINT64_MAX - digit) / 10) fail("a dimension does not fit 64 bits");
        d = d * 10 + digit;
        ++pos_;
      }
      if (pos_ == start) fail(cat("a dimension is not a non-negative integer at byte ", pos_));
      dims.push_back(d);
      if (!peek(')')) expect(',');
    }
    expect(')');
    return dims;
  }

  const std::string& text_;
  const std::string& what_;
  size_t pos_ = 0;
};

}  // namespace

std::string npyHeader(const std::string& descr, const std::vector<uint64_t>& shape) {
  std::string dict =
      cat("{'descr': '", descr, "', 'fortran_order': False, 'shape': ", shapeText(shape), ", }");
  const size_t preamble = kMagicBytes + 2 + 2;  // magic, version, header length
  const size_t unpadded = preamble + dict.size() + 1;
  dict.append((kAlignment - unpadded % kAlignment) % kAlignment, ' ');
  dict.push_back('\n');
  if (dict.size() > 0xffff)
    throw Error(cat("NPY header of dtype '", descr, "' and shape ", shapeText(shape),
                    " is longer than version 1.0 allows"));
  std::string out(kMagic, kMagicBytes);
  out.push_back('\x01');
  out.push_back('\x00');
  appendLittleEndian(out, uint16_t(dict.size()));
  return out + dict;
}

NpyHeader parseNpyHeader(const uint8_t* data, size_t size, const std::string& what) {
  if (size < kMagicBytes + 2 || std::memcmp(data, kMagic, kMagicBytes) != 0)
    throw Error(cat(what, ": not a NumPy .npy file (no \\x93NUMPY magic)"));
  const int major = data[6], minor = data[7];
  if (major < 1 || major > 3 || minor != 0)
    throw Error(cat(what, ": NPY version ", major, ".", minor, " (1.0, 2.0 and 3.0 are read)"));
  const size_t lengthBytes = major == 1 ? 2 : 4;
  const size_t start = kMagicBytes + 2 + lengthBytes;
  if (size < start) throw Error(cat(what, ": truncated NPY header (", size, " bytes)"));
  const uint64_t length = loadLittleEndianBytes(data + kMagicBytes + 2, lengthBytes);
  if (length > size - start)
    throw Error(cat(what, ": truncated NPY header: it claims ", length, " bytes, the file has ",
                    size - start, " after the preamble"));
  const std::string dict(reinterpret_cast<const char*>(data + start), size_t(length));
  NpyHeader h = DictParser(dict, what).parse();
  h.dataOffset = start + size_t(length);
  return h;
}

size_t npyItemBytes(const std::string& descr, const std::string& what) {
  // '<' little-endian, '|' not applicable (one-byte types), then the kind and a byte count
  // (for 'U', a count of UTF-32 code units).
  const auto refuse = [&] {
    return Error(cat(what, ": NPY dtype '", descr,
                     "' is not supported (little-endian b, i, u, f or U types are)"));
  };
  if (descr.size() < 3 || (descr[0] != '<' && descr[0] != '|')) throw refuse();
  const char kind = descr[1];
  size_t count = 0;
  for (size_t k = 2; k < descr.size(); ++k) {
    if (!std::isdigit(static_cast<unsigned char>(descr[k])) || count > 1000000) throw refuse();
    count = count * 10 + size_t(descr[k] - '0');
  }
  switch (kind) {
    case 'b':
      if (count == 1) return 1;
      break;
    case 'i':
    case 'u':
      if (count == 1 || count == 2 || count == 4 || count == 8) return count;
      break;
    case 'f':
      if (count == 2 || count == 4 || count == 8) return count;
      break;
    case 'U':
      if (count >= 1) return 4 * count;
      break;
    default:
      break;
  }
  throw refuse();
}

}  // namespace aperture
