// Wavefront OBJ loader: `v x y z [w]` and `f` with i, i/t, i//n and i/t/n corners, negative
// (relative) indices and polygons (triangulated as fans). Every other statement is ignored.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "core/error.h"
#include "core/mapped_file.h"
#include "core/mesh.h"

namespace aperture {
namespace {

constexpr bool isBlank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/// Per byte: 1 for a blank, 2 for '#' (a comment), 0 for a token character.
struct CharClasses {
  uint8_t of[256] = {};
  constexpr CharClasses() {
    for (int c = 0; c < 256; ++c) of[c] = isBlank(char(c)) ? 1 : c == '#' ? 2 : 0;
  }
};
constexpr CharClasses kCharClasses;

/// The tokens of one line, up to a '#' comment.
class LineTokens {
 public:
  LineTokens(const char* p, const char* end) : p_(p), end_(end) {}
  /// The next token as [b, e); false at the end of the line or at a comment.
  bool next(const char*& b, const char*& e) {
    // A table lookup per character, with a local pointer (kept in a register): the token
    // scan is the OBJ loader's innermost loop.
    const char* p = p_;
    while (p < end_ && kCharClasses.of[uint8_t(*p)] == 1) ++p;
    p_ = p;
    if (p == end_ || *p == '#') return false;
    b = p;
    while (p < end_ && kCharClasses.of[uint8_t(*p)] == 0) ++p;
    e = p_ = p;
    return true;
  }

 private:
  const char* p_;
  const char* end_;
};

struct ForwardRef {
  size_t line;
  int64_t index;
};

/// Parses the statements of one OBJ file into a mesh, line by line.
class ObjParser {
 public:
  ObjParser(const std::string& path, const char* data, Mesh& mesh)
      : path_(path), data_(data), mesh_(mesh), pos_(mesh.positionsDouble) {}

  /// Parses [p, end): every line up to the end of the data.
  void parseLines(const char* p, const char* end) {
    while (p < end) {
      ++line_;
      const char* lineEnd = static_cast<const char*>(std::memchr(p, '\n', size_t(end - p)));
      if (!lineEnd) lineEnd = end;
      parseLine(p, lineEnd);
      p = lineEnd + 1;
    }
  }

  /// Sets the vertex count and checks what could only be checked at the end: the vertex
  /// count, the forward references and that there were faces.
  void finish() {
    mesh_.vertexCount = pos_.size() / 3;
    if (mesh_.vertexCount > std::numeric_limits<uint32_t>::max())
      throw Error(
          cat(path_, ": ", mesh_.vertexCount, " vertices is more than 32-bit indices address"));
    for (const ForwardRef& f : forward_)
      if (f.index > int64_t(mesh_.vertexCount))
        throw Error(cat(path_, ":", f.line, ": face vertex index ", f.index,
                        " is out of range: the file has ", mesh_.vertexCount, " vertices (line ",
                        f.line, ")"));
    if (mesh_.indices.empty())
      throw Error(cat(path_, ": contains no faces (no triangles to render)"));
  }

 private:
  void parseLine(const char* p, const char* lineEnd) {
    if (const void* nul = std::memchr(p, '\0', size_t(lineEnd - p)))
      throw Error(cat(path_, ":", line_, ": binary data (a NUL byte at byte offset ",
                      static_cast<const char*>(nul) - data_, "); an OBJ file is text (line ", line_,
                      ")"));
    LineTokens tok(p, lineEnd);
    const char *b, *e;
    if (!tok.next(b, e)) return;
    const size_t keyLen = size_t(e - b);
    if (keyLen == 1 && *b == 'v')
      parseVertex(tok);
    else if (keyLen == 1 && *b == 'f')
      parseFace(tok);
  }

  /// `v x y z [w]`: the first three coordinates.
  void parseVertex(LineTokens& tok) {
    const char *b, *e;
    double xyz[3];
    for (int a = 0; a < 3; ++a) {
      if (!tok.next(b, e))
        throw Error(cat(path_, ":", line_, ": vertex has ", a,
                        " coordinates, expected 3 coordinates (line ", line_, ")"));
      if (!parseDoubleToken(b, e, xyz[a]))
        throw Error(cat(path_, ":", line_, ": vertex coordinate is not a number: '",
                        printableToken(b, e), "' (line ", line_, ")"));
    }
    pos_.insert(pos_.end(), xyz, xyz + 3);
  }

  /// `f c c c ...`: a polygon, triangulated as a fan.
  void parseFace(LineTokens& tok) {
    const int64_t have = int64_t(pos_.size() / 3);
    const char *b, *e;
    poly_.clear();
    while (tok.next(b, e)) poly_.push_back(cornerIndex(b, e, have));
    if (poly_.size() < 3)
      throw Error(cat(path_, ":", line_, ": face has ", poly_.size(),
                      " vertices, needs at least 3 (line ", line_, ")"));
    ++mesh_.stats.sourceFaces;
    for (size_t k = 1; k + 1 < poly_.size(); ++k) {
      mesh_.indices.push_back(poly_[0]);
      mesh_.indices.push_back(poly_[k]);
      mesh_.indices.push_back(poly_[k + 1]);
    }
  }

  /// The 0-based vertex index of a corner token [b, e) (i, i/t, i//n or i/t/n; negative
  /// indices count back from the `have` vertices read so far).
  uint32_t cornerIndex(const char* b, const char* e, int64_t have) {
    // The vertex index is the part before the first '/'; texture and normal are ignored.
    const char* slash = b;
    while (slash < e && *slash != '/') ++slash;
    int64_t v;
    if (!parseIntToken(b, slash, v)) badIndexToken(b, slash, e);
    if (v == 0)
      throw Error(cat(path_, ":", line_, ": face vertex index 0 (OBJ indices start at 1, line ",
                      line_, ")"));
    if (v < 0) {
      if (v < -have)
        throw Error(cat(path_, ":", line_, ": relative index ", v,
                        " points before the first vertex (", have, " vertices so far, line ", line_,
                        ")"));
      return uint32_t(have + v);
    }
    if (v > int64_t(std::numeric_limits<uint32_t>::max()))
      throw Error(
          cat(path_, ":", line_, ": face vertex index ", v, " is out of range (line ", line_, ")"));
    if (v > have) forward_.push_back({line_, v});
    return uint32_t(v - 1);
  }

  /// Throws for an index [b, slash) that is not an integer: out of range when it is a whole
  /// number too large for int64, not a number otherwise (the message shows the corner [b, e)).
  [[noreturn]] void badIndexToken(const char* b, const char* slash, const char* e) const {
    double d;
    if (parseDoubleToken(b, slash, d) && d == std::floor(d))
      throw Error(cat(path_, ":", line_, ": face vertex index ", printableToken(b, slash),
                      " is out of range (line ", line_, ")"));
    throw Error(cat(path_, ":", line_, ": face vertex index is not a number: '",
                    printableToken(b, e), "' (line ", line_, ")"));
  }

  const std::string& path_;
  const char* data_;
  Mesh& mesh_;
  std::vector<double>& pos_;
  std::vector<uint32_t> poly_;
  /// Indices past the vertices read so far; valid only if the vertex appears later.
  std::vector<ForwardRef> forward_;
  size_t line_ = 0;
};

}  // namespace

Mesh loadObj(const std::string& path) {
  MappedFile file(path);
  return loadObjFromMemory(file.data(), file.size(), path);
}

Mesh loadObjFromMemory(const char* data, size_t size, const std::string& path) {
  if (size == 0) throw Error(cat(path, ": file is empty"));
  if (size >= 4 && std::memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r'))
    throw Error(cat(path, ": this is a PLY file (it starts with 'ply'), not an OBJ file"));
  Mesh mesh;
  mesh.name = path;
  mesh.stats.fileBytes = size;
  ObjParser parser(path, data, mesh);
  parser.parseLines(data, data + size);
  parser.finish();
  return mesh;
}

}  // namespace aperture
