// Wavefront OBJ loader: `v x y z [w]` and `f` with i, i/t, i//n and i/t/n corners, negative
// (relative) indices and polygons (triangulated as fans). With LoadOptions::vertexNormals,
// also `vn` and the corners' normal indices (see loadObj in mesh.h for how vertices used with
// several normals are split). Every other statement is ignored.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/util/error.h"
#include "core/util/mapped_file.h"

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
  ObjParser(const std::string& path, const char* data, Mesh& mesh, bool wantNormals)
      : path_(path),
        data_(data),
        mesh_(mesh),
        pos_(mesh.positionsDouble),
        wantNormals_(wantNormals) {}

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
    if (wantNormals_) attachNormals();
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
    else if (wantNormals_ && keyLen == 2 && b[0] == 'v' && b[1] == 'n')
      parseNormal(tok);
  }

  /// `vn x y z`: a normal, kept only when normals were asked for.
  void parseNormal(LineTokens& tok) {
    const char *b, *e;
    for (int a = 0; a < 3; ++a) {
      double v;
      if (!tok.next(b, e) || !parseDoubleToken(b, e, v))
        throw Error(cat(path_, ":", line_, ": normal 'vn' needs 3 numbers (line ", line_, ")"));
      normals_.push_back(float(v));
    }
  }

  /// The 0-based normal index of corner [b, e) ("i//n" or "i/t/n"), or -1 when it has none.
  int64_t cornerNormal(const char* b, const char* e) {
    const char* first = b;
    while (first < e && *first != '/') ++first;
    if (first == e) return -1;
    const char* second = first + 1;
    while (second < e && *second != '/') ++second;
    if (second == e || second + 1 == e) return -1;
    int64_t n;
    const int64_t have = int64_t(normals_.size() / 3);
    if (!parseIntToken(second + 1, e, n) || n == 0 || n < -have)
      throw Error(cat(path_, ":", line_, ": bad normal index in face corner '",
                      printableToken(b, e), "' (line ", line_, ")"));
    if (n > 0) normalRefs_.push_back({line_, n});
    return n < 0 ? have + n : n - 1;
  }

  /// Per-corner normal indices -> Mesh::vertexNormals. A vertex met with a second normal is
  /// duplicated (its position copied), so each vertex has one normal and no triangle changes
  /// its place. Files whose corners carry no normal indices keep no normals.
  void attachNormals() {
    if (cornerNormals_.empty()) return;
    if (missingNormalLine_)
      throw Error(cat(path_, ":", missingNormalLine_,
                      ": a face corner has no normal index while other corners have one; "
                      "shading normals need a normal on every corner or on none (line ",
                      missingNormalLine_, ")"));
    const int64_t normalCount = int64_t(normals_.size() / 3);
    for (const ForwardRef& f : normalRefs_)
      if (f.index > normalCount)
        throw Error(cat(path_, ":", f.line, ": normal index ", f.index,
                        " is out of range: the file has ", normalCount, " normals (line ", f.line,
                        ")"));
    std::vector<int64_t> normalOf(mesh_.vertexCount, -1);
    std::map<std::pair<uint32_t, int64_t>, uint32_t> copies;
    for (size_t c = 0; c < mesh_.indices.size(); ++c) {
      const uint32_t v = mesh_.indices[c];
      const int64_t n = cornerNormals_[c];
      if (normalOf[v] < 0) normalOf[v] = n;
      if (normalOf[v] == n) continue;
      auto [it, fresh] = copies.emplace(std::pair{v, n}, uint32_t(normalOf.size()));
      if (fresh) {
        for (int a = 0; a < 3; ++a) pos_.push_back(pos_[3 * size_t(v) + size_t(a)]);
        normalOf.push_back(n);
      }
      mesh_.indices[c] = it->second;
    }
    mesh_.vertexCount = normalOf.size();
    if (mesh_.vertexCount > std::numeric_limits<uint32_t>::max())
      throw Error(cat(path_, ": splitting vertices by normal gives ", mesh_.vertexCount,
                      " vertices, more than 32-bit indices address"));
    mesh_.vertexNormals.assign(3 * mesh_.vertexCount, 0.0f);
    for (size_t v = 0; v < normalOf.size(); ++v)
      if (normalOf[v] >= 0)
        for (int a = 0; a < 3; ++a)
          mesh_.vertexNormals[3 * v + size_t(a)] = normals_[3 * size_t(normalOf[v]) + size_t(a)];
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
    polyNormals_.clear();
    while (tok.next(b, e)) {
      poly_.push_back(cornerIndex(b, e, have));
      if (wantNormals_) polyNormals_.push_back(cornerNormal(b, e));
    }
    if (poly_.size() < 3)
      throw Error(cat(path_, ":", line_, ": face has ", poly_.size(),
                      " vertices, needs at least 3 (line ", line_, ")"));
    ++mesh_.stats.sourceFaces;
    for (size_t k = 1; k + 1 < poly_.size(); ++k) {
      mesh_.indices.push_back(poly_[0]);
      mesh_.indices.push_back(poly_[k]);
      mesh_.indices.push_back(poly_[k + 1]);
    }
    if (wantNormals_) keepCornerNormals();
  }

  /// The fan's corner normal indices, in the order of the corners just emitted.
  void keepCornerNormals() {
    for (int64_t n : polyNormals_)
      if (n < 0 && !missingNormalLine_) missingNormalLine_ = line_;
    bool any = false;
    for (int64_t n : polyNormals_) any = any || n >= 0;
    if (any && cornerNormals_.empty() && !mesh_.indices.empty())
      cornerNormals_.assign(mesh_.indices.size() - 3 * (poly_.size() - 2), -1);
    if (!any && cornerNormals_.empty()) return;
    for (size_t k = 1; k + 1 < polyNormals_.size(); ++k) {
      cornerNormals_.push_back(polyNormals_[0]);
      cornerNormals_.push_back(polyNormals_[k]);
      cornerNormals_.push_back(polyNormals_[k + 1]);
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
  // Normals, only with wantNormals_: the `vn` values, each emitted corner's 0-based normal
  // index (-1: none; empty until a corner has one), positive references checked at the end.
  bool wantNormals_;
  std::vector<float> normals_;
  std::vector<int64_t> polyNormals_, cornerNormals_;
  std::vector<ForwardRef> normalRefs_;
  size_t missingNormalLine_ = 0;
};

}  // namespace

Mesh loadObj(const std::string& path, const LoadOptions& options) {
  MappedFile file(path);
  return loadObjFromMemory(file.data(), file.size(), path, options);
}

Mesh loadObjFromMemory(const char* data, size_t size, const std::string& path,
                       const LoadOptions& options) {
  if (size == 0) throw Error(cat(path, ": file is empty"));
  if (!options.properties.empty())
    throw Error(cat(path, ": AOV '", options.properties.front().aovName(),
                    "': an OBJ file has no integer face or vertex properties (PLY files do)"));
  if (size >= 4 && std::memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r'))
    throw Error(cat(path, ": this is a PLY file (it starts with 'ply'), not an OBJ file"));
  Mesh mesh;
  mesh.name = path;
  mesh.stats.fileBytes = size;
  ObjParser parser(path, data, mesh, options.vertexNormals);
  parser.parseLines(data, data + size);
  parser.finish();
  return mesh;
}

}  // namespace aperture
