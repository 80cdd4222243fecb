// Wavefront OBJ loader: `v x y z [w]` and `f` with i, i/t, i//n and i/t/n corners, negative
// (relative) indices and polygons (triangulated as fans). Every other statement is ignored.
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "core/error.h"
#include "core/mapped_file.h"
#include "core/mesh.h"

namespace aperture {
namespace {

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// The tokens of one line, up to a '#' comment.
class LineTokens {
 public:
  LineTokens(const char* p, const char* end) : p_(p), end_(end) {}
  bool next(const char*& b, const char*& e) {
    while (p_ < end_ && isBlank(*p_)) ++p_;
    if (p_ == end_ || *p_ == '#') return false;
    b = p_;
    while (p_ < end_ && !isBlank(*p_) && *p_ != '#') ++p_;
    e = p_;
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

}  // namespace

Mesh loadObj(const std::string& path) {
  MappedFile file(path);
  return loadObjFromMemory(file.data(), file.size(), path);
}

Mesh loadObjFromMemory(const char* data, size_t size, const std::string& path) {
  if (size == 0) throw Error(cat(path, ": file is empty"));
  Mesh mesh;
  mesh.name = path;
  mesh.stats.fileBytes = size;
  std::vector<double>& pos = mesh.positionsDouble;
  std::vector<uint32_t> poly;
  // Indices past the vertices read so far; valid only if the vertex appears later.
  std::vector<ForwardRef> forward;

  const char* p = data;
  const char* end = p + size;
  if (size >= 4 && std::memcmp(p, "ply", 3) == 0 && (p[3] == '\n' || p[3] == '\r'))
    throw Error(cat(path, ": this is a PLY file (it starts with 'ply'), not an OBJ file"));
  size_t line = 0;
  while (p < end) {
    ++line;
    const char* lineEnd = static_cast<const char*>(std::memchr(p, '\n', size_t(end - p)));
    if (!lineEnd) lineEnd = end;
    if (const void* nul = std::memchr(p, '\0', size_t(lineEnd - p)))
      throw Error(cat(path, ":", line, ": binary data (a NUL byte at byte offset ",
                      static_cast<const char*>(nul) - data, "); an OBJ file is text (line ", line,
                      ")"));
    LineTokens tok(p, lineEnd);
    p = lineEnd + 1;
    const char *b, *e;
    if (!tok.next(b, e)) continue;
    const size_t keyLen = size_t(e - b);
    if (keyLen == 1 && *b == 'v') {
      double xyz[3];
      for (int a = 0; a < 3; ++a) {
        if (!tok.next(b, e))
          throw Error(cat(path, ":", line, ": vertex has ", a,
                          " coordinates, expected 3 coordinates (line ", line, ")"));
        if (!parseDoubleToken(b, e, xyz[a]))
          throw Error(cat(path, ":", line, ": vertex coordinate is not a number: '",
                          printableToken(b, e), "' (line ", line, ")"));
      }
      pos.insert(pos.end(), xyz, xyz + 3);
    } else if (keyLen == 1 && *b == 'f') {
      const int64_t have = int64_t(pos.size() / 3);
      poly.clear();
      while (tok.next(b, e)) {
        // The vertex index is the part before the first '/'; texture and normal are ignored.
        const char* slash = b;
        while (slash < e && *slash != '/') ++slash;
        int64_t v;
        if (!parseIntToken(b, slash, v)) {
          double d;
          if (parseDoubleToken(b, slash, d) && d == std::floor(d))
            throw Error(cat(path, ":", line, ": face vertex index ", printableToken(b, slash),
                            " is out of range (line ", line, ")"));
          throw Error(cat(path, ":", line, ": face vertex index is not a number: '",
                          printableToken(b, e), "' (line ", line, ")"));
        }
        if (v == 0)
          throw Error(cat(path, ":", line, ": face vertex index 0 (OBJ indices start at 1, line ",
                          line, ")"));
        if (v < 0) {
          if (v < -have)
            throw Error(cat(path, ":", line, ": relative index ", v,
                            " points before the first vertex (", have, " vertices so far, line ",
                            line, ")"));
          v = have + v;
        } else {
          if (v > int64_t(std::numeric_limits<uint32_t>::max()))
            throw Error(cat(path, ":", line, ": face vertex index ", v, " is out of range (line ",
                            line, ")"));
          if (v > have) forward.push_back({line, v});
          v = v - 1;
        }
        poly.push_back(uint32_t(v));
      }
      if (poly.size() < 3)
        throw Error(cat(path, ":", line, ": face has ", poly.size(),
                        " vertices, needs at least 3 (line ", line, ")"));
      ++mesh.stats.sourceFaces;
      for (size_t k = 1; k + 1 < poly.size(); ++k) {
        mesh.indices.push_back(poly[0]);
        mesh.indices.push_back(poly[k]);
        mesh.indices.push_back(poly[k + 1]);
      }
    }
  }
  mesh.vertexCount = pos.size() / 3;
  if (mesh.vertexCount > std::numeric_limits<uint32_t>::max())
    throw Error(cat(path, ": ", mesh.vertexCount, " vertices is more than 32-bit indices address"));
  for (const ForwardRef& f : forward)
    if (f.index > int64_t(mesh.vertexCount))
      throw Error(cat(path, ":", f.line, ": face vertex index ", f.index,
                      " is out of range: the file has ", mesh.vertexCount, " vertices (line ",
                      f.line, ")"));
  if (mesh.indices.empty()) throw Error(cat(path, ": contains no faces (no triangles to render)"));
  return mesh;
}

}  // namespace aperture
