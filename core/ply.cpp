// PLY loader: ASCII, binary little- and big-endian. Reads vertex x/y/z, `face` polygons
// (triangulated as fans) and `tristrips` (-1 restarts a strip); skips everything else.
// The header's counts are checked against the file size before anything is allocated.
#include <algorithm>
#include <cstring>
#include <limits>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/mapped_file.h"
#include "core/mesh.h"

namespace aperture {
namespace {

enum class PType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

size_t typeSize(PType t) {
  switch (t) {
    case PType::Int8:
    case PType::UInt8:
      return 1;
    case PType::Int16:
    case PType::UInt16:
      return 2;
    case PType::Int32:
    case PType::UInt32:
    case PType::Float32:
      return 4;
    case PType::Float64:
      return 8;
  }
  return 0;
}

bool isInteger(PType t) { return t != PType::Float32 && t != PType::Float64; }

const char* typeName(PType t) {
  switch (t) {
    case PType::Int8:
      return "char";
    case PType::UInt8:
      return "uchar";
    case PType::Int16:
      return "short";
    case PType::UInt16:
      return "ushort";
    case PType::Int32:
      return "int";
    case PType::UInt32:
      return "uint";
    case PType::Float32:
      return "float";
    case PType::Float64:
      return "double";
  }
  return "?";
}

/// Whether an ASCII integer value fits its declared type; -1 is let through for every type
/// (the strip restart marker; a negative face index is reported as such later).
bool fitsType(PType t, int64_t v) {
  if (v == -1) return true;
  switch (t) {
    case PType::Int8:
      return v >= -128 && v <= 127;
    case PType::UInt8:
      return v >= 0 && v <= 255;
    case PType::Int16:
      return v >= -32768 && v <= 32767;
    case PType::UInt16:
      return v >= 0 && v <= 65535;
    case PType::Int32:
      return v >= std::numeric_limits<int32_t>::min() && v <= std::numeric_limits<int32_t>::max();
    case PType::UInt32:
      return v >= 0 && v <= int64_t(std::numeric_limits<uint32_t>::max());
    default:
      return true;
  }
}

bool parseType(std::string_view s, PType& t) {
  struct Name {
    const char* name;
    PType type;
  };
  static const Name names[] = {
      {"char", PType::Int8},       {"int8", PType::Int8},       {"uchar", PType::UInt8},
      {"uint8", PType::UInt8},     {"short", PType::Int16},     {"int16", PType::Int16},
      {"ushort", PType::UInt16},   {"uint16", PType::UInt16},   {"int", PType::Int32},
      {"int32", PType::Int32},     {"uint", PType::UInt32},     {"uint32", PType::UInt32},
      {"float", PType::Float32},   {"float32", PType::Float32}, {"double", PType::Float64},
      {"float64", PType::Float64},
  };
  for (const Name& n : names)
    if (s == n.name) {
      t = n.type;
      return true;
    }
  return false;
}

struct Prop {
  std::string name;
  bool list = false;
  PType type = PType::Float32;     // value type (list items for a list)
  PType countType = PType::UInt8;  // list count type
};

struct Elem {
  std::string name;
  uint64_t count = 0;
  std::vector<Prop> props;
  size_t line = 0;
};

enum class Format { Ascii, BinaryLE, BinaryBE };

constexpr bool kHostLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

template <typename T>
T loadRaw(const char* p, bool swap) {
  T v;
  if (!swap) {
    std::memcpy(&v, p, sizeof(T));
  } else {
    char b[sizeof(T)];
    for (size_t i = 0; i < sizeof(T); ++i) b[i] = p[sizeof(T) - 1 - i];
    std::memcpy(&v, b, sizeof(T));
  }
  return v;
}

double loadDouble(PType t, const char* p, bool swap) {
  switch (t) {
    case PType::Int8:
      return loadRaw<int8_t>(p, swap);
    case PType::UInt8:
      return loadRaw<uint8_t>(p, swap);
    case PType::Int16:
      return loadRaw<int16_t>(p, swap);
    case PType::UInt16:
      return loadRaw<uint16_t>(p, swap);
    case PType::Int32:
      return loadRaw<int32_t>(p, swap);
    case PType::UInt32:
      return loadRaw<uint32_t>(p, swap);
    case PType::Float32:
      return loadRaw<float>(p, swap);
    case PType::Float64:
      return loadRaw<double>(p, swap);
  }
  return 0;
}

int64_t loadInt(PType t, const char* p, bool swap) {
  switch (t) {
    case PType::Int8:
      return loadRaw<int8_t>(p, swap);
    case PType::UInt8:
      return loadRaw<uint8_t>(p, swap);
    case PType::Int16:
      return loadRaw<int16_t>(p, swap);
    case PType::UInt16:
      return loadRaw<uint16_t>(p, swap);
    case PType::Int32:
      return loadRaw<int32_t>(p, swap);
    case PType::UInt32:
      return loadRaw<uint32_t>(p, swap);
    default:
      return 0;  // header validation keeps float types out of integer slots
  }
}

/// Reads values from binary data; every read is bounds-checked and errors give byte offsets.
class BinaryReader {
 public:
  BinaryReader(const std::string& path, const char* base, const char* p, const char* end, bool swap)
      : path_(path), base_(base), p_(p), end_(end), swap_(swap) {}

  std::string where() const { return cat("byte offset ", p_ - base_); }
  const char* pos() const { return p_; }
  void advance(size_t n) { p_ += n; }
  size_t remaining() const { return size_t(end_ - p_); }
  bool swap() const { return swap_; }

  void need(size_t n, const char* what) const {
    if (remaining() < n)
      throw Error(cat(path_, ": truncated data: ", what, " at byte offset ", p_ - base_, " needs ",
                      n, " bytes but the file ends at byte ", end_ - base_));
  }
  double readReal(PType t, const char* what) {
    need(typeSize(t), what);
    double v = loadDouble(t, p_, swap_);
    p_ += typeSize(t);
    return v;
  }
  int64_t readInteger(PType t, const char* what) {
    need(typeSize(t), what);
    int64_t v = loadInt(t, p_, swap_);
    p_ += typeSize(t);
    return v;
  }
  void skipScalar(PType t, const char* what) {
    need(typeSize(t), what);
    p_ += typeSize(t);
  }
  /// Reads a list count and checks that the list fits in the rest of the file.
  uint64_t readListCount(const Prop& prop, const char* what) {
    const char* at = p_;
    int64_t n = readInteger(prop.countType, what);
    if (n < 0)
      throw Error(cat(path_, ": negative list count ", n, " for property '", prop.name,
                      "' at byte offset ", at - base_));
    if (uint64_t(n) > remaining() / typeSize(prop.type))
      throw Error(cat(path_, ": truncated data: list count ", n, " for property '", prop.name,
                      "' at byte offset ", at - base_, " needs ", uint64_t(n) * typeSize(prop.type),
                      " bytes but only ", remaining(), " remain"));
    return uint64_t(n);
  }
  void skipValues(uint64_t n, PType t, const char* what) {
    need(n * typeSize(t), what);
    p_ += n * typeSize(t);
  }

 private:
  const std::string& path_;
  const char* base_;
  const char* p_;
  const char* end_;
  bool swap_;
};

bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

/// Reads whitespace-separated tokens from ASCII data; errors give line numbers and tokens.
class TextReader {
 public:
  TextReader(const std::string& path, const char* p, const char* end, size_t line)
      : path_(path), p_(p), end_(end), line_(line) {}

  std::string where() const { return cat("line ", line_); }
  size_t remaining() const { return size_t(end_ - p_); }

  void token(const char*& b, const char*& e, const char* what) {
    while (p_ < end_ && isSpace(*p_)) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
    if (p_ == end_)
      throw Error(
          cat(path_, ": truncated data: the file ends at line ", line_, " while reading ", what));
    b = p_;
    while (p_ < end_ && !isSpace(*p_)) ++p_;
    e = p_;
  }
  double readReal(PType, const char* what) {
    const char *b, *e;
    token(b, e, what);
    double v;
    if (!parseDoubleToken(b, e, v))
      throw Error(cat(path_, ":", line_, ": ", what, " is not a number: '", printableToken(b, e),
                      "' (line ", line_, ")"));
    return v;
  }
  int64_t readInteger(PType t, const char* what) {
    const char *b, *e;
    token(b, e, what);
    int64_t v;
    if (!parseIntToken(b, e, v)) {
      double d;
      const char* kind = parseDoubleToken(b, e, d) ? "is not an integer" : "is not a number";
      throw Error(cat(path_, ":", line_, ": ", what, " ", kind, ": '", printableToken(b, e),
                      "' (line ", line_, ")"));
    }
    if (!fitsType(t, v))
      throw Error(cat(path_, ":", line_, ": ", what, " ", v, " does not fit the declared type '",
                      typeName(t), "' (line ", line_, ")"));
    return v;
  }
  void skipScalar(PType t, const char* what) { readReal(t, what); }
  uint64_t readListCount(const Prop& prop, const char* what) {
    size_t line = line_;
    int64_t n = readInteger(prop.countType, what);
    if (n < 0)
      throw Error(cat(path_, ":", line, ": negative list count ", n, " for property '", prop.name,
                      "' (line ", line, ")"));
    // Every value takes at least one character and one separator.
    if (uint64_t(n) > remaining() / 2 + 1)
      throw Error(cat(path_, ":", line, ": list count ", n, " for property '", prop.name,
                      "' is larger than the rest of the file (", remaining(), " bytes, line ", line,
                      ")"));
    return uint64_t(n);
  }
  void skipValues(uint64_t n, PType t, const char* what) {
    for (uint64_t i = 0; i < n; ++i) readReal(t, what);
  }

 private:
  const std::string& path_;
  const char* p_;
  const char* end_;
  size_t line_;
};

struct Header {
  Format format = Format::Ascii;
  std::vector<Elem> elems;
  size_t dataOffset = 0;
  size_t dataLine = 1;  // line number of the first data line (ASCII)
};

std::vector<std::string_view> splitWords(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) words.push_back(line.substr(i, j - i));
    i = j;
  }
  return words;
}

/// Longest header accepted; real headers are a few hundred bytes plus comments.
constexpr size_t kMaxHeaderBytes = size_t(1) << 20;

/// One header line at [pos, ...): the line without its newline (and '\r'), and the offset of
/// the next line.
std::string_view headerLine(std::string_view all, size_t pos, size_t& next) {
  size_t nl = all.find('\n', pos);
  size_t lineEnd = nl == std::string_view::npos ? all.size() : nl;
  std::string_view line = all.substr(pos, lineEnd - pos);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  next = nl == std::string_view::npos ? all.size() : nl + 1;
  return line;
}

std::string printable(std::string_view s) { return printableToken(s.data(), s.data() + s.size()); }

Header parseHeader(const std::string& path, const char* data, size_t size) {
  std::string_view all(data, size);
  Header h;
  size_t pos = 0;
  {
    auto first = splitWords(headerLine(all, 0, pos));
    if (first.size() != 1 || first[0] != "ply")
      throw Error(cat(path, ": not a PLY file (the first line is not 'ply')"));
  }
  // First pass: find end_header (within kMaxHeaderBytes) without storing the lines, so a
  // file of millions of short lines costs no memory.
  const size_t headerStart = pos;
  const std::string_view window = all.substr(0, std::min(size, kMaxHeaderBytes));
  size_t lineCount = 1;
  bool terminated = false;
  for (size_t p = pos; p < window.size();) {
    size_t next;
    auto words = splitWords(headerLine(window, p, next));
    ++lineCount;
    if (words.size() == 1 && words[0] == "end_header" &&
        (next < window.size() || window.size() == size)) {
      terminated = true;
      h.dataOffset = next;
      h.dataLine = lineCount + 1;
      break;
    }
    p = next;
  }
  if (!terminated) {
    if (size > kMaxHeaderBytes)
      throw Error(cat(path, ": unterminated header: no end_header line in the first ",
                      kMaxHeaderBytes, " bytes"));
    throw Error(cat(path, ": unterminated header: no end_header line"));
  }
  const std::string_view body = all.substr(0, h.dataOffset);
  bool haveFormat = false;
  size_t lineNo = 1;
  for (size_t at = headerStart; at < body.size();) {
    ++lineNo;
    size_t next;
    const std::string_view line = headerLine(body, at, next);
    at = next;
    if (at >= body.size()) break;  // the end_header line
    auto w = splitWords(line);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "format") {
      if (w.size() != 3)
        throw Error(cat(path, ":", lineNo, ": bad format line '", printable(line), "'"));
      if (w[1] == "ascii") {
        h.format = Format::Ascii;
      } else if (w[1] == "binary_little_endian") {
        h.format = Format::BinaryLE;
      } else if (w[1] == "binary_big_endian") {
        h.format = Format::BinaryBE;
      } else {
        throw Error(cat(path, ":", lineNo, ": unknown format '", printable(w[1]),
                        "' (expected ascii, binary_little_endian or binary_big_endian)"));
      }
      if (w[2] != "1.0")
        throw Error(cat(path, ":", lineNo, ": unsupported PLY version '", printable(w[2]), "'"));
      haveFormat = true;
    } else if (w[0] == "element") {
      if (w.size() != 3)
        throw Error(cat(path, ":", lineNo, ": bad element line '", printable(line), "'"));
      Elem e;
      e.name = std::string(w[1]);
      e.line = lineNo;
      int64_t n;
      if (!parseIntToken(w[2].data(), w[2].data() + w[2].size(), n) || n < 0)
        throw Error(cat(path, ":", lineNo, ": bad element count '", printable(w[2]),
                        "' for element '", printable(e.name), "'"));
      e.count = uint64_t(n);
      for (const Elem& other : h.elems)
        if (other.name == e.name)
          throw Error(cat(path, ":", lineNo, ": duplicate element '", printable(e.name), "'"));
      h.elems.push_back(std::move(e));
    } else if (w[0] == "property") {
      if (h.elems.empty()) throw Error(cat(path, ":", lineNo, ": property before any element"));
      Prop p;
      if (w.size() == 5 && w[1] == "list") {
        p.list = true;
        if (!parseType(w[2], p.countType))
          throw Error(cat(path, ":", lineNo, ": unknown property type '", printable(w[2]), "'"));
        if (!isInteger(p.countType))
          throw Error(cat(path, ":", lineNo, ": list count type '", printable(w[2]),
                          "' is not an integer type"));
        if (!parseType(w[3], p.type))
          throw Error(cat(path, ":", lineNo, ": unknown property type '", printable(w[3]), "'"));
        p.name = std::string(w[4]);
      } else if (w.size() == 3 && w[1] != "list") {
        if (!parseType(w[1], p.type))
          throw Error(cat(path, ":", lineNo, ": unknown property type '", printable(w[1]), "'"));
        p.name = std::string(w[2]);
      } else {
        throw Error(cat(path, ":", lineNo, ": bad property line '", printable(line), "'"));
      }
      h.elems.back().props.push_back(std::move(p));
    } else {
      throw Error(cat(path, ":", lineNo, ": unknown header line '", printable(line), "'"));
    }
  }
  if (!haveFormat) throw Error(cat(path, ": missing 'format' line in the header"));

  // Every item needs a minimum number of bytes; reject counts the file cannot hold.
  const size_t dataBytes = size - h.dataOffset;
  double total = 0;
  for (const Elem& e : h.elems) {
    if (e.props.empty()) continue;
    size_t minItem = 0;
    for (const Prop& p : e.props)
      minItem += h.format == Format::Ascii ? 2 : typeSize(p.list ? p.countType : p.type);
    double need = double(e.count) * double(minItem);
    total += need;
    if (need > double(dataBytes) + 1 || total > double(dataBytes) + 1)
      throw Error(cat(path, ":", e.line, ": element '", e.name, "' claims ", e.count,
                      " items (at least ", need, " bytes in all, ", total,
                      " with the elements before it), larger than the file: only ", dataBytes,
                      " bytes follow the header"));
  }
  return h;
}

int findProp(const Elem& e, const char* name) {
  for (size_t i = 0; i < e.props.size(); ++i)
    if (e.props[i].name == name) return int(i);
  return -1;
}

uint32_t checkedIndex(const std::string& path, int64_t v, const std::string& where) {
  if (v < 0) throw Error(cat(path, ": negative vertex index ", v, " at ", where));
  if (v > int64_t(std::numeric_limits<uint32_t>::max()))
    throw Error(cat(path, ": vertex index ", v, " at ", where, " is out of range"));
  return uint32_t(v);
}

void emitFan(std::vector<uint32_t>& out, const uint32_t* poly, size_t n) {
  for (size_t k = 1; k + 1 < n; ++k) {
    out.push_back(poly[0]);
    out.push_back(poly[k]);
    out.push_back(poly[k + 1]);
  }
}

template <typename Reader>
void readVertices(const std::string& path, const Elem& e, Reader& r, Mesh& mesh) {
  int ix = findProp(e, "x"), iy = findProp(e, "y"), iz = findProp(e, "z");
  const char* axes = "xyz";
  int idx[3] = {ix, iy, iz};
  bool useDouble = false;
  for (int a = 0; a < 3; ++a) {
    if (idx[a] < 0)
      throw Error(cat(path, ":", e.line, ": element 'vertex' has no '", axes[a], "' property"));
    if (e.props[idx[a]].list)
      throw Error(cat(path, ":", e.line, ": vertex property '", axes[a], "' is a list"));
    useDouble = useDouble || e.props[idx[a]].type == PType::Float64;
  }
  if (e.count > std::numeric_limits<uint32_t>::max())
    throw Error(cat(path, ": ", e.count, " vertices is more than 32-bit indices can address"));
  mesh.vertexCount = size_t(e.count);
  if (useDouble)
    mesh.positionsDouble.resize(3 * mesh.vertexCount);
  else
    mesh.positions.resize(3 * mesh.vertexCount);
  double xyz[3] = {0, 0, 0};
  for (uint64_t i = 0; i < e.count; ++i) {
    for (size_t k = 0; k < e.props.size(); ++k) {
      const Prop& p = e.props[k];
      if (p.list) {
        uint64_t n = r.readListCount(p, "a vertex list count");
        r.skipValues(n, p.type, "a vertex list value");
      } else if (int(k) == ix || int(k) == iy || int(k) == iz) {
        xyz[int(k) == ix ? 0 : int(k) == iy ? 1 : 2] = r.readReal(p.type, "a vertex coordinate");
      } else {
        r.skipScalar(p.type, "a vertex property");
      }
    }
    if (useDouble)
      for (int a = 0; a < 3; ++a) mesh.positionsDouble[3 * i + a] = xyz[a];
    else
      for (int a = 0; a < 3; ++a) mesh.positions[3 * i + a] = float(xyz[a]);
  }
}

int findIndexList(const std::string& path, const Elem& e, bool allowVertexIndex) {
  int k = findProp(e, "vertex_indices");
  if (k < 0 && allowVertexIndex) k = findProp(e, "vertex_index");
  if (k < 0)
    throw Error(
        cat(path, ":", e.line, ": element '", e.name, "' has no vertex_indices list property"));
  const Prop& p = e.props[k];
  if (!p.list)
    throw Error(
        cat(path, ":", e.line, ": property '", p.name, "' of '", e.name, "' is not a list"));
  if (!isInteger(p.type))
    throw Error(cat(path, ":", e.line, ": index type of '", p.name, "' is not an integer type"));
  return k;
}

/// Faces (polygons, triangulated as fans) or strips; `strips` selects the -1 restart rule.
template <typename Reader>
void readFaces(const std::string& path, const Elem& e, Reader& r, Mesh& mesh, bool strips) {
  int li = findIndexList(path, e, !strips);
  std::vector<uint32_t> poly;
  for (uint64_t i = 0; i < e.count; ++i) {
    for (size_t k = 0; k < e.props.size(); ++k) {
      const Prop& p = e.props[k];
      if (!p.list) {
        r.skipScalar(p.type, "a face property");
        continue;
      }
      uint64_t n = r.readListCount(p, "a list count");
      if (int(k) != li) {
        r.skipValues(n, p.type, "a list value");
        continue;
      }
      poly.clear();
      for (uint64_t j = 0; j < n; ++j) {
        int64_t v = r.readInteger(p.type, "a vertex index");
        if (strips && v == -1) {
          if (!poly.empty()) ++mesh.stats.sourceFaces;
          poly.clear();
          continue;
        }
        if (v < 0 || v > int64_t(std::numeric_limits<uint32_t>::max()))
          checkedIndex(path, v, cat(r.where(), " (", e.name, " ", i, ")"));
        poly.push_back(uint32_t(v));
        size_t m = poly.size();
        if (strips && m >= 3) {
          // Standard strip order: every other triangle swaps its first two vertices.
          bool odd = ((m - 3) & 1) != 0;
          mesh.indices.push_back(poly[m - (odd ? 2 : 3)]);
          mesh.indices.push_back(poly[m - (odd ? 3 : 2)]);
          mesh.indices.push_back(poly[m - 1]);
        }
      }
      if (strips) {
        if (!poly.empty()) ++mesh.stats.sourceFaces;
      } else {
        ++mesh.stats.sourceFaces;
        emitFan(mesh.indices, poly.data(), poly.size());
      }
    }
  }
}

/// Fast path for the common binary face layout: one list with a uchar count and 32-bit
/// indices in host byte order.
bool readFacesFast(const std::string& path, const Elem& e, BinaryReader& r, Mesh& mesh) {
  if (e.props.size() != 1 || r.swap()) return false;
  const Prop& p = e.props[0];
  if (!p.list || p.countType != PType::UInt8 ||
      (p.type != PType::Int32 && p.type != PType::UInt32) ||
      (p.name != "vertex_indices" && p.name != "vertex_index"))
    return false;
  const bool isSigned = p.type == PType::Int32;
  mesh.indices.reserve(mesh.indices.size() + 3 * e.count);
  uint32_t poly[255];
  for (uint64_t i = 0; i < e.count; ++i) {
    r.need(1, "a face list count");
    const size_t n = static_cast<unsigned char>(*r.pos());
    r.advance(1);
    r.need(4 * n, "a face's vertex indices");
    std::memcpy(poly, r.pos(), 4 * n);
    uint32_t bits = 0;
    for (size_t k = 0; k < n; ++k) bits |= poly[k];
    if (isSigned && (bits & 0x80000000u)) {
      for (size_t k = 0; k < n; ++k)
        if (poly[k] & 0x80000000u)
          checkedIndex(path, int32_t(poly[k]), cat(r.where(), " (face ", i, ")"));
    }
    r.advance(4 * n);
    ++mesh.stats.sourceFaces;
    if (n == 3) {
      mesh.indices.insert(mesh.indices.end(), poly, poly + 3);
    } else {
      emitFan(mesh.indices, poly, n);
    }
  }
  return true;
}

/// Fast path for vertices that are exactly float x, y, z in host byte order.
bool readVerticesFast(const Elem& e, BinaryReader& r, Mesh& mesh) {
  if (r.swap() || e.props.size() != 3 || e.count > std::numeric_limits<uint32_t>::max())
    return false;
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a)
    if (e.props[a].list || e.props[a].type != PType::Float32 || e.props[a].name != names[a])
      return false;
  r.need(12 * e.count, "vertex data");
  mesh.vertexCount = size_t(e.count);
  mesh.positions.resize(3 * mesh.vertexCount);
  if (e.count) std::memcpy(mesh.positions.data(), r.pos(), 12 * e.count);
  r.advance(12 * e.count);
  return true;
}

template <typename Reader>
void skipElement(const Elem& e, Reader& r) {
  // An element without properties takes no bytes, whatever its count.
  if (e.props.empty()) return;
  for (uint64_t i = 0; i < e.count; ++i)
    for (const Prop& p : e.props) {
      if (p.list)
        r.skipValues(r.readListCount(p, "a list count"), p.type, "a list value");
      else
        r.skipScalar(p.type, "a property value");
    }
}

bool fixedSize(const Elem& e, size_t& bytes) {
  bytes = 0;
  for (const Prop& p : e.props) {
    if (p.list) return false;
    bytes += typeSize(p.type);
  }
  return true;
}

}  // namespace

Mesh loadPly(const std::string& path) {
  MappedFile file(path);
  return loadPlyFromMemory(file.data(), file.size(), path);
}

Mesh loadPlyFromMemory(const char* data, size_t size, const std::string& path) {
  if (size == 0) throw Error(cat(path, ": file is empty"));
  Header h = parseHeader(path, data, size);
  Mesh mesh;
  mesh.name = path;
  mesh.stats.fileBytes = size;

  const Elem* vertexElem = nullptr;
  bool haveFaces = false;
  for (const Elem& e : h.elems) {
    if (e.name == "vertex") vertexElem = &e;
    if (e.name == "face" || e.name == "tristrips") haveFaces = true;
  }
  if (!vertexElem) throw Error(cat(path, ": no 'vertex' element in the header"));
  if (!haveFaces) throw Error(cat(path, ": no face or tristrips element in the header"));

  const char* begin = data + h.dataOffset;
  const char* end = data + size;
  if (h.format == Format::Ascii) {
    TextReader r(path, begin, end, h.dataLine);
    for (const Elem& e : h.elems) {
      if (e.name == "vertex")
        readVertices(path, e, r, mesh);
      else if (e.name == "face" || e.name == "tristrips")
        readFaces(path, e, r, mesh, e.name == "tristrips");
      else
        skipElement(e, r);
    }
  } else {
    bool swap = (h.format == Format::BinaryBE) == kHostLittleEndian;
    BinaryReader r(path, data, begin, end, swap);
    for (const Elem& e : h.elems) {
      size_t itemBytes;
      if (e.name == "vertex") {
        if (!readVerticesFast(e, r, mesh)) readVertices(path, e, r, mesh);
      } else if (e.name == "face") {
        if (!readFacesFast(path, e, r, mesh)) readFaces(path, e, r, mesh, false);
      } else if (e.name == "tristrips") {
        readFaces(path, e, r, mesh, true);
      } else if (fixedSize(e, itemBytes)) {
        r.skipValues(e.count * itemBytes, PType::UInt8, "skipped element data");
      } else {
        skipElement(e, r);
      }
    }
  }
  if (mesh.indices.empty()) throw Error(cat(path, ": contains no faces (no triangles to render)"));
  return mesh;
}

}  // namespace aperture
