// PLY loader: ASCII, binary little- and big-endian. Reads vertex x/y/z, `face` polygons
// (triangulated as fans) and `tristrips` (-1 restarts a strip); skips everything else unless
// LoadOptions asks for it: integer face/vertex properties (MeshProperty) and vertex normals
// (nx ny nz). Requests turn off the binary fast paths only for the elements that carry them
// (those elements have more than the fast paths' properties anyway).
// Binary elements of fixed-size items (vertices without list properties; faces whose counts
// all equal the first) are parsed in parallel, straight into the mesh's buffers; anything
// else, and any item the parallel readers find wrong, goes to the serial readers, so the mesh
// and the error messages are the same either way (tests/core/mesh/test_ply_parallel.cpp).
// The header's counts are checked against the file size before anything is allocated.
#include "core/mesh/ply.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string_view>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/huge_pages.h"
#include "core/util/mapped_file.h"
#include "core/util/parallel.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {

bool isInteger(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

const char* typeName(PlyType t) {
  switch (t) {
    case PlyType::Int8:
      return "char";
    case PlyType::UInt8:
      return "uchar";
    case PlyType::Int16:
      return "short";
    case PlyType::UInt16:
      return "ushort";
    case PlyType::Int32:
      return "int";
    case PlyType::UInt32:
      return "uint";
    case PlyType::Float32:
      return "float";
    case PlyType::Float64:
      return "double";
  }
  return "?";
}

/// Whether an ASCII integer value fits its declared type; -1 is let through for every type
/// (the strip restart marker; a negative face index is reported as such later).
bool fitsType(PlyType t, int64_t v) {
  if (v == -1) return true;
  switch (t) {
    case PlyType::Int8:
      return v >= -128 && v <= 127;
    case PlyType::UInt8:
      return v >= 0 && v <= 255;
    case PlyType::Int16:
      return v >= -32768 && v <= 32767;
    case PlyType::UInt16:
      return v >= 0 && v <= 65535;
    case PlyType::Int32:
      return v >= std::numeric_limits<int32_t>::min() && v <= std::numeric_limits<int32_t>::max();
    case PlyType::UInt32:
      return v >= 0 && v <= int64_t(std::numeric_limits<uint32_t>::max());
    default:
      return true;
  }
}

bool parseType(std::string_view s, PlyType& t) {
  struct Name {
    const char* name;
    PlyType type;
  };
  static const Name names[] = {
      {"char", PlyType::Int8},       {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},     {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16},   {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},     {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32},   {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64},
  };
  for (const Name& n : names)
    if (s == n.name) {
      t = n.type;
      return true;
    }
  return false;
}

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

int64_t loadInt(PlyType t, const char* p, bool swap) {
  switch (t) {
    case PlyType::Int8:
      return loadRaw<int8_t>(p, swap);
    case PlyType::UInt8:
      return loadRaw<uint8_t>(p, swap);
    case PlyType::Int16:
      return loadRaw<int16_t>(p, swap);
    case PlyType::UInt16:
      return loadRaw<uint16_t>(p, swap);
    case PlyType::Int32:
      return loadRaw<int32_t>(p, swap);
    case PlyType::UInt32:
      return loadRaw<uint32_t>(p, swap);
    default:
      return 0;  // header validation keeps float types out of integer slots
  }
}

double loadDouble(PlyType t, const char* p, bool swap) {
  if (t == PlyType::Float32) return loadRaw<float>(p, swap);
  if (t == PlyType::Float64) return loadRaw<double>(p, swap);
  return double(loadInt(t, p, swap));  // every integer type fits int64 and double exactly
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
  double readReal(PlyType t, const char* what) {
    need(plyTypeSize(t), what);
    double v = loadDouble(t, p_, swap_);
    p_ += plyTypeSize(t);
    return v;
  }
  int64_t readInteger(PlyType t, const char* what) {
    need(plyTypeSize(t), what);
    int64_t v = loadInt(t, p_, swap_);
    p_ += plyTypeSize(t);
    return v;
  }
  void skipScalar(PlyType t, const char* what) {
    need(plyTypeSize(t), what);
    p_ += plyTypeSize(t);
  }
  /// Reads a list count and checks that the list fits in the rest of the file.
  uint64_t readListCount(const PlyProperty& prop, const char* what) {
    const char* at = p_;
    int64_t n = readInteger(prop.countType, what);
    if (n < 0)
      throw Error(cat(path_, ": negative list count ", n, " for property '", prop.name,
                      "' at byte offset ", at - base_));
    if (uint64_t(n) > remaining() / plyTypeSize(prop.type))
      throw Error(cat(path_, ": truncated data: list count ", n, " for property '", prop.name,
                      "' at byte offset ", at - base_, " needs ",
                      uint64_t(n) * plyTypeSize(prop.type), " bytes but only ", remaining(),
                      " remain"));
    return uint64_t(n);
  }
  void skipValues(uint64_t n, PlyType t, const char* what) {
    need(n * plyTypeSize(t), what);
    p_ += n * plyTypeSize(t);
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
  double readReal(PlyType, const char* what) {
    const char *b, *e;
    token(b, e, what);
    double v;
    if (!parseDoubleToken(b, e, v))
      throw Error(cat(path_, ":", line_, ": ", what, " is not a number: '", printableToken(b, e),
                      "' (line ", line_, ")"));
    return v;
  }
  int64_t readInteger(PlyType t, const char* what) {
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
  void skipScalar(PlyType t, const char* what) { readReal(t, what); }
  uint64_t readListCount(const PlyProperty& prop, const char* what) {
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
  void skipValues(uint64_t n, PlyType t, const char* what) {
    for (uint64_t i = 0; i < n; ++i) readReal(t, what);
  }

 private:
  const std::string& path_;
  const char* p_;
  const char* end_;
  size_t line_;
};

using Words = std::vector<std::string_view>;

Words splitWords(std::string_view line) {
  Words words;
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

/// The offset of the line after the first; throws unless the first line is "ply".
size_t skipMagicLine(const std::string& path, std::string_view all) {
  size_t next = 0;
  const Words first = splitWords(headerLine(all, 0, next));
  if (first.size() != 1 || first[0] != "ply")
    throw Error(cat(path, ": not a PLY file (the first line is not 'ply')"));
  return next;
}

/// Finds the end_header line (within kMaxHeaderBytes) and sets the data offset and the first
/// data line. The lines are not stored, so a file of millions of short lines costs no memory.
void findEndHeader(const std::string& path, std::string_view all, size_t from, PlyHeader& h) {
  const std::string_view window = all.substr(0, std::min(all.size(), kMaxHeaderBytes));
  size_t lineCount = 1;
  for (size_t p = from; p < window.size();) {
    size_t next;
    const Words words = splitWords(headerLine(window, p, next));
    ++lineCount;
    if (words.size() == 1 && words[0] == "end_header" &&
        (next < window.size() || window.size() == all.size())) {
      h.dataOffset = next;
      h.dataLine = lineCount + 1;
      return;
    }
    p = next;
  }
  if (all.size() > kMaxHeaderBytes)
    throw Error(cat(path, ": unterminated header: no end_header line in the first ",
                    kMaxHeaderBytes, " bytes"));
  throw Error(cat(path, ": unterminated header: no end_header line"));
}

/// A header line with what messages need to point at it.
struct HeaderLine {
  const std::string& path;
  size_t number;
  std::string_view text;
  Words words;
};

/// Throws Error("path:line: what").
[[noreturn]] void headerError(const HeaderLine& l, const std::string& what) {
  throw Error(cat(l.path, ":", l.number, ": ", what));
}

PlyType propertyType(const HeaderLine& l, std::string_view name) {
  PlyType t;
  if (!parseType(name, t)) headerError(l, cat("unknown property type '", printable(name), "'"));
  return t;
}

PlyFormat parseFormatLine(const HeaderLine& l) {
  const Words& w = l.words;
  if (w.size() != 3) headerError(l, cat("bad format line '", printable(l.text), "'"));
  PlyFormat format = PlyFormat::Ascii;
  if (w[1] == "binary_little_endian") {
    format = PlyFormat::BinaryLittleEndian;
  } else if (w[1] == "binary_big_endian") {
    format = PlyFormat::BinaryBigEndian;
  } else if (w[1] != "ascii") {
    headerError(l, cat("unknown format '", printable(w[1]),
                       "' (expected ascii, binary_little_endian or binary_big_endian)"));
  }
  if (w[2] != "1.0") headerError(l, cat("unsupported PLY version '", printable(w[2]), "'"));
  return format;
}

PlyElement parseElementLine(const HeaderLine& l, const std::vector<PlyElement>& before) {
  const Words& w = l.words;
  if (w.size() != 3) headerError(l, cat("bad element line '", printable(l.text), "'"));
  PlyElement e;
  e.name = std::string(w[1]);
  e.line = l.number;
  int64_t n;
  if (!parseIntToken(w[2].data(), w[2].data() + w[2].size(), n) || n < 0)
    headerError(
        l, cat("bad element count '", printable(w[2]), "' for element '", printable(e.name), "'"));
  e.count = uint64_t(n);
  for (const PlyElement& other : before)
    if (other.name == e.name) headerError(l, cat("duplicate element '", printable(e.name), "'"));
  return e;
}

PlyProperty parsePropertyLine(const HeaderLine& l) {
  const Words& w = l.words;
  PlyProperty p;
  if (w.size() == 5 && w[1] == "list") {
    p.list = true;
    p.countType = propertyType(l, w[2]);
    if (!isInteger(p.countType))
      headerError(l, cat("list count type '", printable(w[2]), "' is not an integer type"));
    p.type = propertyType(l, w[3]);
    p.name = std::string(w[4]);
  } else if (w.size() == 3 && w[1] != "list") {
    p.type = propertyType(l, w[1]);
    p.name = std::string(w[2]);
  } else {
    headerError(l, cat("bad property line '", printable(l.text), "'"));
  }
  return p;
}

/// Applies one line between the first and end_header to `h`; sets haveFormat on a format line.
void parseHeaderLine(const HeaderLine& l, PlyHeader& h, bool& haveFormat) {
  const Words& w = l.words;
  if (w.empty() || w[0] == "comment" || w[0] == "obj_info") return;
  if (w[0] == "format") {
    h.format = parseFormatLine(l);
    haveFormat = true;
  } else if (w[0] == "element") {
    h.elements.push_back(parseElementLine(l, h.elements));
  } else if (w[0] == "property") {
    if (h.elements.empty()) headerError(l, "property before any element");
    h.elements.back().props.push_back(parsePropertyLine(l));
  } else {
    headerError(l, cat("unknown header line '", printable(l.text), "'"));
  }
}

/// Parses the lines of `body` (the header up to and including end_header) from `from` on;
/// false when there was no format line.
bool parseHeaderLines(const std::string& path, std::string_view body, size_t from, PlyHeader& h) {
  bool haveFormat = false;
  size_t lineNo = 1;
  for (size_t at = from; at < body.size();) {
    ++lineNo;
    size_t next;
    const std::string_view line = headerLine(body, at, next);
    at = next;
    if (at >= body.size()) break;  // the end_header line
    parseHeaderLine(HeaderLine{path, lineNo, line, splitWords(line)}, h, haveFormat);
  }
  return haveFormat;
}

}  // namespace

PlyHeader readPlyHeader(const std::string& path, const char* data, size_t size) {
  const std::string_view all(data, size);
  PlyHeader h;
  const size_t headerStart = skipMagicLine(path, all);
  findEndHeader(path, all, headerStart, h);
  if (!parseHeaderLines(path, all.substr(0, h.dataOffset), headerStart, h))
    throw Error(cat(path, ": missing 'format' line in the header"));
  return h;
}

uint64_t plyMinItemBytes(PlyFormat format, const PlyElement& e) {
  uint64_t bytes = 0;
  for (const PlyProperty& p : e.props)
    bytes += format == PlyFormat::Ascii ? 2 : plyTypeSize(p.list ? p.countType : p.type);
  return bytes;
}

void checkPlyCountsFitData(const std::string& path, const PlyHeader& h, uint64_t dataBytes) {
  double total = 0;
  for (const PlyElement& e : h.elements) {
    if (e.props.empty()) continue;
    const double need = double(e.count) * double(plyMinItemBytes(h.format, e));
    total += need;
    if (need > double(dataBytes) + 1 || total > double(dataBytes) + 1)
      throw Error(cat(path, ":", e.line, ": element '", e.name, "' claims ", e.count,
                      " items (at least ", need, " bytes in all, ", total,
                      " with the elements before it), larger than the file: only ", dataBytes,
                      " bytes follow the header"));
  }
}

namespace {

int findProp(const PlyElement& e, const char* name) {
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

void emitFan(LargeBuffer<uint32_t>& out, const uint32_t* poly, size_t n) {
  for (size_t k = 1; k + 1 < n; ++k) {
    out.push_back(poly[0]);
    out.push_back(poly[k]);
    out.push_back(poly[k + 1]);
  }
}

/// What the loader keeps of one element beyond positions and indices: for each of the
/// element's properties, the index in Mesh::properties its values go to (-1: not kept), and
/// for the vertex element the properties holding nx ny nz (-1 when not kept).
struct ElementRequest {
  std::vector<int> slotOf;
  int normal[3] = {-1, -1, -1};
  bool keepsNormals() const { return normal[0] >= 0; }
};

/// The names of e's scalar integer properties (those a MeshProperty can come from).
std::vector<std::string> integerPropertyNames(const PlyElement& e) {
  std::vector<std::string> names;
  for (const PlyProperty& p : e.props)
    if (!p.list && isInteger(p.type)) names.push_back(p.name);
  return names;
}

/// Maps the requested properties of `domain` to e's properties; throws Error naming the file,
/// the element and the property when e lacks it, or has it as a float or a list.
ElementRequest requestOf(const std::string& path, const PlyElement& e, PropertyDomain domain,
                         const LoadOptions& options) {
  ElementRequest req;
  req.slotOf.assign(e.props.size(), -1);
  for (size_t slot = 0; slot < options.properties.size(); ++slot) {
    const PropertyAov& want = options.properties[slot];
    if (want.domain != domain) continue;
    const int k = findProp(e, want.name.c_str());
    const std::vector<std::string> have = integerPropertyNames(e);
    const std::string listing = have.empty() ? "it has no integer properties"
                                             : cat("its integer properties: ", join(have, ", "));
    if (k < 0)
      throw Error(cat(path, ":", e.line, ": AOV '", want.aovName(), "': element '", e.name,
                      "' has no property '", want.name, "'", didYouMean(want.name, have), "; ",
                      listing));
    const PlyProperty& p = e.props[size_t(k)];
    if (p.list || !isInteger(p.type))
      throw Error(cat(path, ":", e.line, ": AOV '", want.aovName(), "': property '", want.name,
                      "' of '", e.name, "' is ", p.list ? "a list" : typeName(p.type),
                      ", not an integer (ids must be integers); ", listing));
    req.slotOf[size_t(k)] = int(slot);
  }
  if (domain == PropertyDomain::Vertex && options.vertexNormals) {
    const int n[3] = {findProp(e, "nx"), findProp(e, "ny"), findProp(e, "nz")};
    bool all = true;
    for (int a = 0; a < 3; ++a) all = all && n[a] >= 0 && !e.props[size_t(n[a])].list;
    if (all)
      for (int a = 0; a < 3; ++a) req.normal[a] = n[a];
  }
  return req;
}

/// Stores a property value as the Mesh contract says: signed values as their 32-bit two's
/// complement (the cast of int64 to uint32 is modulo 2^32), unsigned ones as they are.
inline uint32_t propertyValue(int64_t v) { return uint32_t(v); }

template <typename Reader>
void readVertices(const std::string& path, const PlyElement& e, Reader& r, Mesh& mesh,
                  const ElementRequest& req) {
  int ix = findProp(e, "x"), iy = findProp(e, "y"), iz = findProp(e, "z");
  const char* axes = "xyz";
  int idx[3] = {ix, iy, iz};
  bool useDouble = false;
  for (int a = 0; a < 3; ++a) {
    if (idx[a] < 0)
      throw Error(cat(path, ":", e.line, ": element 'vertex' has no '", axes[a], "' property"));
    if (e.props[idx[a]].list)
      throw Error(cat(path, ":", e.line, ": vertex property '", axes[a], "' is a list"));
    useDouble = useDouble || e.props[idx[a]].type == PlyType::Float64;
  }
  if (e.count > std::numeric_limits<uint32_t>::max())
    throw Error(cat(path, ": ", e.count, " vertices is more than 32-bit indices can address"));
  mesh.vertexCount = size_t(e.count);
  if (useDouble)
    resizeOnHugePages(mesh.positionsDouble, 3 * mesh.vertexCount);
  else
    resizeOnHugePages(mesh.positions, 3 * mesh.vertexCount);
  if (req.keepsNormals()) resizeOnHugePages(mesh.vertexNormals, 3 * mesh.vertexCount);
  for (size_t k = 0; k < e.props.size(); ++k)
    if (req.slotOf[k] >= 0)
      resizeOnHugePages(mesh.properties[size_t(req.slotOf[k])].values, mesh.vertexCount);
  double xyz[3] = {0, 0, 0};
  for (uint64_t i = 0; i < e.count; ++i) {
    for (size_t k = 0; k < e.props.size(); ++k) {
      const PlyProperty& p = e.props[k];
      if (p.list) {
        uint64_t n = r.readListCount(p, "a vertex list count");
        r.skipValues(n, p.type, "a vertex list value");
      } else if (int(k) == ix || int(k) == iy || int(k) == iz) {
        xyz[int(k) == ix ? 0 : int(k) == iy ? 1 : 2] = r.readReal(p.type, "a vertex coordinate");
      } else if (req.slotOf[k] >= 0) {
        mesh.properties[size_t(req.slotOf[k])].values[i] =
            propertyValue(r.readInteger(p.type, "a vertex property"));
      } else if (req.keepsNormals() &&
                 (int(k) == req.normal[0] || int(k) == req.normal[1] || int(k) == req.normal[2])) {
        const int a = int(k) == req.normal[0] ? 0 : int(k) == req.normal[1] ? 1 : 2;
        mesh.vertexNormals[3 * i + size_t(a)] = float(r.readReal(p.type, "a vertex normal"));
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

int findIndexList(const std::string& path, const PlyElement& e, bool allowVertexIndex) {
  int k = findProp(e, "vertex_indices");
  if (k < 0 && allowVertexIndex) k = findProp(e, "vertex_index");
  if (k < 0)
    throw Error(
        cat(path, ":", e.line, ": element '", e.name, "' has no vertex_indices list property"));
  const PlyProperty& p = e.props[k];
  if (!p.list)
    throw Error(
        cat(path, ":", e.line, ": property '", p.name, "' of '", e.name, "' is not a list"));
  if (!isInteger(p.type))
    throw Error(cat(path, ":", e.line, ": index type of '", p.name, "' is not an integer type"));
  return k;
}

/// Faces (polygons, triangulated as fans) or strips; `strips` selects the -1 restart rule.
/// A requested face property's value goes on every triangle its face or strip yields.
template <typename Reader>
void readFaces(const std::string& path, const PlyElement& e, Reader& r, Mesh& mesh, bool strips,
               const ElementRequest& req) {
  int li = findIndexList(path, e, !strips);
  std::vector<uint32_t> poly;
  std::vector<uint32_t> itemValues(mesh.properties.size(), 0);
  bool anyKept = false;
  for (int slot : req.slotOf) anyKept = anyKept || slot >= 0;
  for (uint64_t i = 0; i < e.count; ++i) {
    const size_t trianglesBefore = mesh.indices.size() / 3;
    for (size_t k = 0; k < e.props.size(); ++k) {
      const PlyProperty& p = e.props[k];
      if (!p.list) {
        if (req.slotOf[k] >= 0)
          itemValues[size_t(req.slotOf[k])] =
              propertyValue(r.readInteger(p.type, "a face property"));
        else
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
    if (anyKept) {
      const size_t made = mesh.indices.size() / 3 - trianglesBefore;
      for (size_t k = 0; k < e.props.size(); ++k)
        if (req.slotOf[k] >= 0) {
          std::vector<uint32_t>& values = mesh.properties[size_t(req.slotOf[k])].values;
          values.insert(values.end(), made, itemValues[size_t(req.slotOf[k])]);
        }
    }
  }
}

/// Fast path for the common binary face layout: one list with a uchar count and 32-bit
/// indices in host byte order. Kept out of line, so its loop is compiled the same whatever
/// loadPlyFromMemory inlines around it (inlined, the crown took ~1% more instructions after an
/// unrelated change to the header code).
[[gnu::noinline]] bool readFacesFast(const std::string& path, const PlyElement& e, BinaryReader& r,
                                     Mesh& mesh) {
  if (e.props.size() != 1 || r.swap()) return false;
  const PlyProperty& p = e.props[0];
  if (!p.list || p.countType != PlyType::UInt8 ||
      (p.type != PlyType::Int32 && p.type != PlyType::UInt32) ||
      (p.name != "vertex_indices" && p.name != "vertex_index"))
    return false;
  const bool isSigned = p.type == PlyType::Int32;
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
bool readVerticesFast(const PlyElement& e, BinaryReader& r, Mesh& mesh) {
  if (r.swap() || e.props.size() != 3 || e.count > std::numeric_limits<uint32_t>::max())
    return false;
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a)
    if (e.props[a].list || e.props[a].type != PlyType::Float32 || e.props[a].name != names[a])
      return false;
  r.need(12 * e.count, "vertex data");
  mesh.vertexCount = size_t(e.count);
  resizeOnHugePages(mesh.positions, 3 * mesh.vertexCount);
  if (e.count) std::memcpy(mesh.positions.data(), r.pos(), 12 * e.count);
  r.advance(12 * e.count);
  return true;
}

template <typename Reader>
void skipElement(const PlyElement& e, Reader& r) {
  // An element without properties takes no bytes, whatever its count.
  if (e.props.empty()) return;
  for (uint64_t i = 0; i < e.count; ++i)
    for (const PlyProperty& p : e.props) {
      if (p.list)
        r.skipValues(r.readListCount(p, "a list count"), p.type, "a list value");
      else
        r.skipScalar(p.type, "a property value");
    }
}

bool fixedSize(const PlyElement& e, size_t& bytes) {
  bytes = 0;
  for (const PlyProperty& p : e.props) {
    if (p.list) return false;
    bytes += plyTypeSize(p.type);
  }
  return true;
}

/// Records per task of the parallel parsers: large enough that a task outweighs its
/// scheduling, small enough that two cores share a mesh evenly.
constexpr size_t kRecordsPerTask = size_t(1) << 16;

/// Where one scalar of a fixed-size vertex record goes: a coordinate, a kept property or a
/// normal component (`which`: the axis or the property slot).
struct VertexField {
  enum Kind { Coordinate, Property, Normal } kind;
  int which;
  size_t offset;  ///< bytes from the start of the record
  PlyType type;
};

/// The fields readVertices would fill from one item of `e`, with the same precedence
/// (coordinates, then kept properties, then normals); everything else is skipped.
std::vector<VertexField> vertexFields(const PlyElement& e, const int xyz[3],
                                      const ElementRequest& req) {
  std::vector<VertexField> fields;
  size_t offset = 0;
  for (size_t k = 0; k < e.props.size(); ++k) {
    const PlyProperty& p = e.props[k];
    const int ki = int(k);
    if (ki == xyz[0] || ki == xyz[1] || ki == xyz[2])
      fields.push_back({VertexField::Coordinate,
                        ki == xyz[0]   ? 0
                        : ki == xyz[1] ? 1
                                       : 2,
                        offset, p.type});
    else if (req.slotOf[k] >= 0)
      fields.push_back({VertexField::Property, req.slotOf[k], offset, p.type});
    else if (req.keepsNormals() &&
             (ki == req.normal[0] || ki == req.normal[1] || ki == req.normal[2]))
      fields.push_back({VertexField::Normal,
                        ki == req.normal[0]   ? 0
                        : ki == req.normal[1] ? 1
                                              : 2,
                        offset, p.type});
    offset += plyTypeSize(p.type);
  }
  return fields;
}

/// Parallel reader of a vertex element whose items all have the same size (no list property)
/// and fit in the data; false (nothing read) otherwise, and the serial readers take over and
/// report the problem. Values go through the same conversions as in the serial readers, so
/// the mesh is bit for bit the same: an exactly float x y z layout in host order is copied
/// (as readVerticesFast does), any other goes through double (as readVertices does).
bool readVerticesParallel(const PlyElement& e, BinaryReader& r, Mesh& mesh,
                          const ElementRequest& req) {
  size_t itemBytes;
  if (!fixedSize(e, itemBytes) || itemBytes == 0 ||
      e.count > std::numeric_limits<uint32_t>::max() || e.count > r.remaining() / itemBytes)
    return false;
  const int xyz[3] = {findProp(e, "x"), findProp(e, "y"), findProp(e, "z")};
  if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) return false;
  const char* const items = r.pos();
  const size_t n = size_t(e.count);
  const bool copyFloats = itemBytes == 12 && e.props.size() == 3 && !r.swap() && xyz[0] == 0 &&
                          xyz[1] == 1 && xyz[2] == 2 && e.props[0].type == PlyType::Float32 &&
                          e.props[1].type == PlyType::Float32 &&
                          e.props[2].type == PlyType::Float32;
  bool useDouble = false;
  for (int a = 0; a < 3; ++a)
    useDouble = useDouble || e.props[size_t(xyz[a])].type == PlyType::Float64;
  mesh.vertexCount = n;
  // finishMesh pads the float positions for Embree in place: room for the padding now saves
  // it a copy of the whole buffer.
  if (!useDouble) reserveOnHugePages(mesh.positions, 3 * n + kVertexPaddingFloats);
  if (copyFloats) {
    mesh.positions.resize(3 * n);
    parallelFor(n, kRecordsPerTask, [&](size_t b, size_t end) {
      std::memcpy(mesh.positions.data() + 3 * b, items + 12 * b, 12 * (end - b));
    });
    r.advance(12 * n);
    return true;
  }
  if (useDouble)
    resizeOnHugePages(mesh.positionsDouble, 3 * n);
  else
    mesh.positions.resize(3 * n);
  if (req.keepsNormals()) resizeOnHugePages(mesh.vertexNormals, 3 * n);
  for (int slot : req.slotOf)
    if (slot >= 0) resizeOnHugePages(mesh.properties[size_t(slot)].values, n);
  const std::vector<VertexField> fields = vertexFields(e, xyz, req);
  const bool swap = r.swap();
  parallelFor(n, kRecordsPerTask, [&](size_t b, size_t end) {
    for (size_t i = b; i < end; ++i) {
      const char* item = items + i * itemBytes;
      for (const VertexField& f : fields) {
        const char* at = item + f.offset;
        if (f.kind == VertexField::Coordinate) {
          const double v = loadDouble(f.type, at, swap);
          if (useDouble)
            mesh.positionsDouble[3 * i + size_t(f.which)] = v;
          else
            mesh.positions[3 * i + size_t(f.which)] = float(v);
        } else if (f.kind == VertexField::Property) {
          mesh.properties[size_t(f.which)].values[i] = propertyValue(loadInt(f.type, at, swap));
        } else {
          mesh.vertexNormals[3 * i + size_t(f.which)] = float(loadDouble(f.type, at, swap));
        }
      }
    }
  });
  r.advance(itemBytes * n);
  return true;
}

/// Writes faces [b, end) of `items` (a uchar count, then `corners` 32-bit indices in host
/// order) to `out` as fans; false when a count differs from `corners` or an index has
/// `signBit` set (a negative signed index). kCorners, when not 0, is `corners` known at
/// compile time: for triangles (readTriangleRange's last face, and every face without SSE2)
/// each face is then three loads and three stores, without a call or an inner loop.
template <size_t kCorners>
bool readFanRange(const char* items, size_t corners, uint32_t signBit, size_t b, size_t end,
                  uint32_t* out) {
  if (kCorners) corners = kCorners;
  const size_t itemBytes = 1 + 4 * corners;
  uint32_t poly[255];
  bool regular = true;
  for (size_t i = b; i < end; ++i) {
    const char* item = items + i * itemBytes;
    std::memcpy(poly, item + 1, 4 * corners);
    uint32_t bits = 0;
    for (size_t k = 0; k < corners; ++k) bits |= poly[k];
    regular &= static_cast<unsigned char>(*item) == corners && !(bits & signBit);
    for (size_t k = 1; k + 1 < corners; ++k) {
      *out++ = poly[0];
      *out++ = poly[k];
      *out++ = poly[k + 1];
    }
  }
  return regular;
}

/// readFanRange for triangles, with SSE2: each face is one 16-byte load (its 13 bytes and 3
/// of the next face's) whose indices, shifted down a byte, are stored as 16 bytes (the 4 past
/// the triangle are overwritten by the next one); counts and sign bits are checked once, on
/// bits gathered over the range. The range's last face, whose load or store would reach past
/// the range, goes through readFanRange<3>, as every face does without SSE2.
bool readTriangleRange(const char* items, uint32_t signBit, size_t b, size_t end, uint32_t* out) {
#if defined(__SSE2__)
  if (end - b < 2) return readFanRange<3>(items, 3, signBit, b, end, out);
  const __m128i three = _mm_cvtsi32_si128(3);
  __m128i countBits = _mm_setzero_si128(), indexBits = _mm_setzero_si128();
  const char* item = items + 13 * b;
  uint32_t* triangle = out;
  for (size_t i = b; i + 1 < end; ++i, item += 13, triangle += 3) {
    const __m128i face = _mm_loadu_si128(reinterpret_cast<const __m128i*>(item));
    const __m128i indices = _mm_srli_si128(face, 1);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(triangle), indices);
    countBits = _mm_or_si128(countBits, _mm_xor_si128(face, three));  // byte 0: count ^ 3
    indexBits = _mm_or_si128(indexBits, indices);
  }
  uint32_t bits[4];
  _mm_storeu_si128(reinterpret_cast<__m128i*>(bits), indexBits);
  const bool regular =
      (_mm_cvtsi128_si32(countBits) & 0xFF) == 0 && !((bits[0] | bits[1] | bits[2]) & signBit);
  return readFanRange<3>(items, 3, signBit, end - 1, end, triangle) && regular;
#else
  return readFanRange<3>(items, 3, signBit, b, end, out);
#endif
}

/// Parallel reader of the layout readFacesFast reads (one list: uchar count, 32-bit indices in
/// host order) when every face has the count of the first, so items have a fixed size: each
/// task checks its counts and indices and writes its fans in place. False, with the mesh as it
/// was, when a count differs, a signed index is negative or the faces do not fit in the data:
/// the serial reader then reads them (and reports the error at the same place as ever).
bool readFacesParallel(const PlyElement& e, BinaryReader& r, Mesh& mesh) {
  if (e.props.size() != 1 || r.swap() || e.count == 0 || r.remaining() == 0) return false;
  const PlyProperty& p = e.props[0];
  if (!p.list || p.countType != PlyType::UInt8 ||
      (p.type != PlyType::Int32 && p.type != PlyType::UInt32) ||
      (p.name != "vertex_indices" && p.name != "vertex_index"))
    return false;
  const size_t corners = static_cast<unsigned char>(*r.pos());
  const size_t itemBytes = 1 + 4 * corners;
  if (e.count > r.remaining() / itemBytes) return false;
  const size_t faces = size_t(e.count);
  const size_t indicesPerFace = corners >= 3 ? 3 * (corners - 2) : 0;
  const uint32_t signBit = p.type == PlyType::Int32 ? 0x80000000u : 0u;
  const size_t before = mesh.indices.size();
  resizeOnHugePages(mesh.indices, before + indicesPerFace * faces);
  const char* const items = r.pos();
  std::atomic<bool> irregular{false};
  parallelFor(faces, kRecordsPerTask, [&](size_t b, size_t end) {
    uint32_t* out = mesh.indices.data() + before + indicesPerFace * b;
    const bool regular = corners == 3 ? readTriangleRange(items, signBit, b, end, out)
                                      : readFanRange<0>(items, corners, signBit, b, end, out);
    if (!regular) irregular.store(true, std::memory_order_relaxed);
  });
  if (irregular.load()) {
    mesh.indices.resize(before);
    return false;
  }
  mesh.stats.sourceFaces += faces;
  r.advance(itemBytes * faces);
  return true;
}

/// APERTURE_PLY_SERIAL=1 in the environment (read once) makes loadPlyFromMemory use only the
/// serial binary readers, to compare them with the parallel ones.
PlyParsing parsingFromEnvironment() {
  static const PlyParsing parsing = [] {
    const char* v = std::getenv("APERTURE_PLY_SERIAL");
    return v && std::string_view(v) == "1" ? PlyParsing::Serial : PlyParsing::Parallel;
  }();
  return parsing;
}

}  // namespace

Mesh loadPly(const std::string& path, const LoadOptions& options) {
  MappedFile file(path);
  return loadPlyFromMemory(file.data(), file.size(), path, options);
}

Mesh loadPlyFromMemory(const char* data, size_t size, const std::string& path,
                       const LoadOptions& options) {
  return loadPlyFromMemory(data, size, path, options, parsingFromEnvironment());
}

Mesh loadPlyFromMemory(const char* data, size_t size, const std::string& path,
                       const LoadOptions& options, PlyParsing parsing) {
  if (size == 0) throw Error(cat(path, ": file is empty"));
  const PlyHeader h = readPlyHeader(path, data, size);
  checkPlyCountsFitData(path, h, size - h.dataOffset);
  Mesh mesh;
  mesh.name = path;
  mesh.stats.fileBytes = size;

  const PlyElement* vertexElem = nullptr;
  bool haveFaces = false;
  for (const PlyElement& e : h.elements) {
    if (e.name == "vertex") vertexElem = &e;
    if (e.name == "face" || e.name == "tristrips") haveFaces = true;
  }
  if (!vertexElem) throw Error(cat(path, ": no 'vertex' element in the header"));
  const bool readsFaces = !options.verticesOnly;
  if (!haveFaces && readsFaces)
    throw Error(cat(path, ": no face or tristrips element in the header"));
  for (const PropertyAov& p : options.properties) mesh.properties.push_back({p.domain, p.name, {}});
  auto requestFor = [&](const PlyElement& e) {
    return requestOf(path, e, e.name == "vertex" ? PropertyDomain::Vertex : PropertyDomain::Face,
                     options);
  };

  const char* begin = data + h.dataOffset;
  const char* end = data + size;
  if (h.format == PlyFormat::Ascii) {
    TextReader r(path, begin, end, h.dataLine);
    for (const PlyElement& e : h.elements) {
      if (e.name == "vertex")
        readVertices(path, e, r, mesh, requestFor(e));
      else if (readsFaces && (e.name == "face" || e.name == "tristrips"))
        readFaces(path, e, r, mesh, e.name == "tristrips", requestFor(e));
      else
        skipElement(e, r);
    }
  } else {
    bool swap = (h.format == PlyFormat::BinaryBigEndian) == kHostLittleEndian;
    BinaryReader r(path, data, begin, end, swap);
    for (const PlyElement& e : h.elements) {
      size_t itemBytes;
      // The fast paths read elements with exactly the positions or the index list, so they
      // never see a requested property or normal (requestFor has checked it exists).
      const bool parallel = parsing == PlyParsing::Parallel;
      if (e.name == "vertex") {
        const ElementRequest req = requestFor(e);
        if (!(parallel && readVerticesParallel(e, r, mesh, req)) && !readVerticesFast(e, r, mesh))
          readVertices(path, e, r, mesh, req);
      } else if (readsFaces && e.name == "face") {
        const ElementRequest req = requestFor(e);
        if (!(parallel && readFacesParallel(e, r, mesh)) && !readFacesFast(path, e, r, mesh))
          readFaces(path, e, r, mesh, false, req);
      } else if (readsFaces && e.name == "tristrips") {
        readFaces(path, e, r, mesh, true, requestFor(e));
      } else if (fixedSize(e, itemBytes)) {
        r.skipValues(e.count * itemBytes, PlyType::UInt8, "skipped element data");
      } else {
        skipElement(e, r);
      }
    }
  }
  if (mesh.indices.empty() && readsFaces)
    throw Error(cat(path, ": contains no faces (no triangles to render)"));
  return mesh;
}

}  // namespace aperture
