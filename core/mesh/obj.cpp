// Wavefront OBJ loader. Always: `v x y z [w]` and `f` with i, i/t, i//n and i/t/n corners,
// negative (relative) indices and polygons (triangulated as fans, a polygon's triangles in
// fan order). When LoadOptions asks:
// - vertexNormals: `vn` and the corners' normal indices;
// - texcoords: `vt u [v [w]]` and the corners' texture indices, stored as (u, 1 - v) so that
//   (0, 0) is the top-left of the image (SurfaceTexture's convention, glTF's);
//   a vertex used with several (vt, vn) pairs is split into one vertex per pair (see loadObj
//   in mesh.h);
// - groups: `o NAME` and `g NAME...` (the rest of the line is the name) start objects, each
//   distinct name an id in order of first appearance; faces before any o/g (or after an o/g
//   without a name) belong to an object named after the file's stem -> Mesh::faceGroups;
// - materials: `usemtl NAME`, each distinct name an id in order of first appearance; faces
//   before any usemtl (or after a usemtl without a name) use a material "default" whose id
//   follows the named ones -> Mesh::faceMaterials.
// loadObjScene also reads the `mtllib` files (core/mesh/mtl.h: newmtl, Kd, map_Kd) and fills
// the names and materials of a SceneFile. Every other statement is ignored.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/mtl.h"
#include "core/mesh/scene_file.h"
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
  /// The rest of the line as [b, e): from the next token to the end of the last one (blanks
  /// between tokens kept), up to a comment; false when no token is left.
  bool rest(const char*& b, const char*& e) {
    const char *tb, *te;
    if (!next(tb, te)) return false;
    b = tb;
    e = te;
    while (next(tb, te)) e = te;
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

/// What a face corner references besides its vertex: a texture coordinate (`vt`, the
/// corner's second index) or a normal (`vn`, its third).
struct CornerAttribute {
  const char* what;  ///< "texture coordinate", "normal": in messages
  const char* rule;  ///< why every corner or none needs one: in messages
  size_t width;      ///< floats stored per value
  std::vector<float> values;
  /// The current polygon's corners' 0-based indices, then every emitted corner's (-1: none;
  /// empty until a corner has one).
  std::vector<int64_t> poly, corners;
  std::vector<ForwardRef> refs;  ///< positive indices, checked against the count at the end
  size_t missingLine = 0;        ///< the first line with a corner that has none
  int64_t count() const { return int64_t(values.size() / width); }
};

/// Names in order of first appearance, each with its id.
class NameIds {
 public:
  uint32_t idOf(const std::string& name) {
    auto [it, fresh] = ids_.emplace(name, uint32_t(names_.size()));
    if (fresh) names_.push_back(name);
    return it->second;
  }
  std::vector<std::string>& names() { return names_; }

 private:
  std::unordered_map<std::string, uint32_t> ids_;
  std::vector<std::string> names_;
};

/// A `mtllib` file the OBJ names.
struct LibraryRef {
  size_t line;
  std::string name;  ///< as written
  std::string path;  ///< resolved beside the OBJ
};

/// What the OBJ's statements beyond geometry named.
struct ObjNames {
  std::vector<std::string> objects;    ///< by object id
  std::vector<std::string> materials;  ///< by material id; "default" last when defaultMaterial
  bool defaultMaterial = false;        ///< faces without a usemtl exist
  std::vector<LibraryRef> libraries;   ///< in file order (scene loads only)
};

/// The material id of faces before any usemtl until the end, when its id is known.
constexpr uint32_t kDefaultMaterial = std::numeric_limits<uint32_t>::max();

/// The last path component without its extension ("room" for "scenes/room.obj").
std::string fileStem(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = name.find_last_of('.');
  if (dot != std::string::npos && dot > 0) name.resize(dot);
  return name;
}

/// Parses the statements of one OBJ file into a mesh, line by line.
class ObjParser {
 public:
  /// `names`: also read mtllib statements and track object and material names (scene loads);
  /// null for a single mesh, which tracks names only when groups or materials are asked for.
  ObjParser(const std::string& path, const char* data, Mesh& mesh, const LoadOptions& options,
            ObjNames* names)
      : path_(path),
        data_(data),
        mesh_(mesh),
        pos_(mesh.positionsDouble),
        wantNormals_(options.vertexNormals),
        wantTexcoords_(options.texcoords),
        wantCorners_(options.vertexNormals || options.texcoords),
        wantGroups_(options.groups),
        wantMaterials_(options.materials),
        trackNames_(names || options.groups || options.materials),
        wantExtras_(wantCorners_ || trackNames_),
        names_(names) {}

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
    if (wantCorners_) attachCornerAttributes();
    if (trackNames_) finishNames();
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
    if (keyLen == 1 && *b == 'v') {
      parseVertex(tok);
    } else if (keyLen == 1 && *b == 'f') {
      parseFace(tok);
    } else if (wantExtras_) {
      parseOtherStatement(b, keyLen, tok);
    }
  }

  /// The statements read only when asked for: vn, vt and the names (out of line, so that the
  /// v and f loop stays as tight as without them).
  [[gnu::noinline]] void parseOtherStatement(const char* b, size_t keyLen, LineTokens& tok) {
    if (keyLen == 2 && b[0] == 'v' && (b[1] == 'n' || b[1] == 't')) {
      if (b[1] == 'n' && wantNormals_) parseNormal(tok);
      if (b[1] == 't' && wantTexcoords_) parseTexcoord(tok);
    } else if (trackNames_) {
      parseNameStatement(b, keyLen, tok);
    }
  }

  /// `o NAME`, `g NAME...`, `usemtl NAME` (the name is the rest of the line; without one,
  /// back to the default object or material) and, for a scene, `mtllib FILE...`.
  void parseNameStatement(const char* key, size_t keyLen, LineTokens& tok) {
    const char *b, *e;
    if (keyLen == 1 && (*key == 'o' || *key == 'g')) {
      currentObject_ = tok.rest(b, e) ? int64_t(objects_.idOf(std::string(b, e))) : -1;
    } else if (keyLen == 6 && std::memcmp(key, "usemtl", 6) == 0) {
      currentMaterial_ = tok.rest(b, e) ? int64_t(materials_.idOf(std::string(b, e))) : -1;
    } else if (names_ && keyLen == 6 && std::memcmp(key, "mtllib", 6) == 0) {
      bool any = false;
      while (tok.next(b, e)) {
        const std::string name(b, e);
        names_->libraries.push_back({line_, name, pathBeside(path_, name)});
        any = true;
      }
      if (!any) throw Error(cat(path_, ":", line_, ": mtllib without a file name"));
    }
  }

  /// `vn x y z`: a normal, kept only when normals were asked for.
  void parseNormal(LineTokens& tok) {
    const char *b, *e;
    for (int a = 0; a < 3; ++a) {
      double v;
      if (!tok.next(b, e) || !parseDoubleToken(b, e, v))
        throw Error(cat(path_, ":", line_, ": normal 'vn' needs 3 numbers (line ", line_, ")"));
      normals_.values.push_back(float(v));
    }
  }

  /// `vt u [v [w]]`: stored as (u, 1 - v) (v = 0 when absent), kept only when asked for.
  void parseTexcoord(LineTokens& tok) {
    const char *b, *e;
    double uv[2] = {0, 0};
    for (int a = 0; a < 2; ++a) {
      if (!tok.next(b, e)) {
        if (a == 1) break;
        throw Error(cat(path_, ":", line_, ": texture coordinate 'vt' needs 1 to 3 numbers (line ",
                        line_, ")"));
      }
      if (!parseDoubleToken(b, e, uv[a]))
        throw Error(cat(path_, ":", line_, ": texture coordinate is not a number: '",
                        printableToken(b, e), "' (line ", line_, ")"));
    }
    texcoords_.values.push_back(float(uv[0]));
    texcoords_.values.push_back(float(1.0 - uv[1]));
  }

  /// The corner [b, e)'s texture and normal indices, as far as they are asked for.
  void parseCornerAttributes(const char* b, const char* e) {
    const char* first = b;
    while (first < e && *first != '/') ++first;
    const char* second = first == e ? e : first + 1;
    while (second < e && *second != '/') ++second;
    if (wantTexcoords_)
      texcoords_.poly.push_back(first == e ? -1
                                           : attributeIndex(texcoords_, b, e, first + 1, second));
    if (wantNormals_)
      normals_.poly.push_back(second == e ? -1 : attributeIndex(normals_, b, e, second + 1, e));
  }

  /// The 0-based index [ib, ie) of corner [b, e) into `attr`, or -1 when it is empty.
  int64_t attributeIndex(CornerAttribute& attr, const char* b, const char* e, const char* ib,
                         const char* ie) {
    if (ib == ie) return -1;
    int64_t n;
    const int64_t have = attr.count();
    if (!parseIntToken(ib, ie, n) || n == 0 || n < -have)
      throw Error(cat(path_, ":", line_, ": bad ", attr.what, " index in face corner '",
                      printableToken(b, e), "' (line ", line_, ")"));
    if (n > 0) attr.refs.push_back({line_, n});
    return n < 0 ? have + n : n - 1;
  }

  /// Throws for a corner of `attr` that had none while others had one, or for an index past
  /// the values the file has.
  void checkCorners(const CornerAttribute& attr) const {
    if (attr.missingLine)
      throw Error(cat(path_, ":", attr.missingLine, ": a face corner has no ", attr.what,
                      " index while other corners have one; ", attr.rule, " (line ",
                      attr.missingLine, ")"));
    for (const ForwardRef& f : attr.refs)
      if (f.index > attr.count())
        throw Error(cat(path_, ":", f.line, ": ", attr.what, " index ", f.index,
                        " is out of range: the file has ", attr.count(), " ", attr.what, "s (line ",
                        f.line, ")"));
  }

  /// Per-corner texture and normal indices -> Mesh::texcoords and Mesh::vertexNormals. A
  /// vertex met with a second (texture, normal) pair is duplicated (its position copied), so
  /// each vertex has one pair and no triangle changes its place. An attribute no corner has
  /// is not kept.
  void attachCornerAttributes() {
    const bool texcoords = !texcoords_.corners.empty(), normals = !normals_.corners.empty();
    if (!texcoords && !normals) return;
    if (texcoords) checkCorners(texcoords_);
    if (normals) checkCorners(normals_);
    using Pair = std::pair<int64_t, int64_t>;  // (vt, vn), -1 for one not kept
    const Pair unset{-2, -2};
    std::vector<Pair> pairOf(mesh_.vertexCount, unset);
    std::map<std::tuple<uint32_t, int64_t, int64_t>, uint32_t> copies;
    for (size_t c = 0; c < mesh_.indices.size(); ++c) {
      const uint32_t v = mesh_.indices[c];
      const Pair p{texcoords ? texcoords_.corners[c] : -1, normals ? normals_.corners[c] : -1};
      if (pairOf[v] == unset) pairOf[v] = p;
      if (pairOf[v] == p) continue;
      auto [it, fresh] = copies.emplace(std::tuple{v, p.first, p.second}, uint32_t(pairOf.size()));
      if (fresh) {
        for (int a = 0; a < 3; ++a) pos_.push_back(pos_[3 * size_t(v) + size_t(a)]);
        pairOf.push_back(p);
      }
      mesh_.indices[c] = it->second;
    }
    mesh_.vertexCount = pairOf.size();
    if (mesh_.vertexCount > std::numeric_limits<uint32_t>::max())
      throw Error(cat(path_, ": splitting vertices by texture coordinate and normal gives ",
                      mesh_.vertexCount, " vertices, more than 32-bit indices address"));
    if (texcoords) mesh_.texcoords = gather(texcoords_, pairOf, &Pair::first);
    if (normals) mesh_.vertexNormals = gather(normals_, pairOf, &Pair::second);
  }

  /// Each vertex's value of `attr` (its index in member `which` of its pair), 0 for none.
  template <class Pair>
  static std::vector<float> gather(const CornerAttribute& attr, const std::vector<Pair>& pairOf,
                                   int64_t Pair::*which) {
    std::vector<float> out(attr.width * pairOf.size(), 0.0f);
    for (size_t v = 0; v < pairOf.size(); ++v) {
      const int64_t k = pairOf[v].*which;
      if (k >= 0)
        for (size_t a = 0; a < attr.width; ++a)
          out[attr.width * v + a] = attr.values[attr.width * size_t(k) + a];
    }
    return out;
  }

  /// The names in id order; the faces without a usemtl get the id after the named materials.
  void finishNames() {
    std::vector<std::string> materials = std::move(materials_.names());
    const bool defaultUsed = defaultMaterialUsed_;
    if (defaultUsed) {
      const uint32_t id = uint32_t(materials.size());
      materials.push_back("default");
      for (uint32_t& m : mesh_.faceMaterials)
        if (m == kDefaultMaterial) m = id;
    }
    if (names_) {
      names_->objects = std::move(objects_.names());
      names_->materials = std::move(materials);
      names_->defaultMaterial = defaultUsed;
    }
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
    const LineTokens corners = tok;
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
    if (wantExtras_) parseFaceExtras(corners);
  }

  /// What a face holds beyond its vertex indices, as far as it is asked for: its corners'
  /// texture and normal indices (a second scan of the corners [tok...), so that the plain
  /// geometry loop stays as tight as without them) and its object and material.
  [[gnu::noinline]] void parseFaceExtras(LineTokens tok) {
    if (wantCorners_) {
      texcoords_.poly.clear();
      normals_.poly.clear();
      const char *b, *e;
      while (tok.next(b, e)) parseCornerAttributes(b, e);
      if (wantTexcoords_) keepCorners(texcoords_);
      if (wantNormals_) keepCorners(normals_);
    }
    if (trackNames_) keepFaceIds(poly_.size() - 2);
  }

  /// The fan's corner indices of `attr`, in the order of the corners just emitted.
  void keepCorners(CornerAttribute& attr) {
    bool any = false;
    for (int64_t n : attr.poly) {
      if (n < 0 && !attr.missingLine) attr.missingLine = line_;
      any = any || n >= 0;
    }
    if (any && attr.corners.empty() && !mesh_.indices.empty())
      attr.corners.assign(mesh_.indices.size() - 3 * (poly_.size() - 2), -1);
    if (!any && attr.corners.empty()) return;
    for (size_t k = 1; k + 1 < attr.poly.size(); ++k) {
      attr.corners.push_back(attr.poly[0]);
      attr.corners.push_back(attr.poly[k]);
      attr.corners.push_back(attr.poly[k + 1]);
    }
  }

  /// The object and material ids of the polygon's `triangles` triangles.
  void keepFaceIds(size_t triangles) {
    if (currentObject_ < 0) currentObject_ = int64_t(objects_.idOf(fileStem(path_)));
    if (currentMaterial_ < 0) defaultMaterialUsed_ = true;
    if (wantGroups_)
      mesh_.faceGroups.insert(mesh_.faceGroups.end(), triangles, uint32_t(currentObject_));
    if (wantMaterials_)
      mesh_.faceMaterials.insert(
          mesh_.faceMaterials.end(), triangles,
          currentMaterial_ < 0 ? kDefaultMaterial : uint32_t(currentMaterial_));
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
  // What LoadOptions asks for (wantCorners_: texture coordinates or normals).
  bool wantNormals_, wantTexcoords_, wantCorners_, wantGroups_, wantMaterials_;
  CornerAttribute texcoords_{"texture coordinate",
                             "texture coordinates need a vt on every corner or on none",
                             2,
                             {},
                             {},
                             {},
                             {},
                             0};
  CornerAttribute normals_{
      "normal", "shading normals need a normal on every corner or on none", 3, {}, {}, {}, {}, 0};
  // Objects and materials: tracked for a scene or when groups or materials are asked for.
  bool trackNames_;
  bool wantExtras_;  ///< wantCorners_ or trackNames_: a face needs parseFaceExtras
  ObjNames* names_;
  NameIds objects_, materials_;
  int64_t currentObject_ = -1, currentMaterial_ = -1;  // -1: the default one
  bool defaultMaterialUsed_ = false;
};

/// The OBJ at `data` as one mesh; with `names`, also its object, material and library names.
Mesh parseObj(const char* data, size_t size, const std::string& path, const LoadOptions& options,
              ObjNames* names) {
  if (size == 0) throw Error(cat(path, ": file is empty"));
  if (!options.properties.empty())
    throw Error(cat(path, ": AOV '", options.properties.front().aovName(),
                    "': an OBJ file has no integer face or vertex properties (PLY files do)"));
  if (size >= 4 && std::memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r'))
    throw Error(cat(path, ": this is a PLY file (it starts with 'ply'), not an OBJ file"));
  Mesh mesh;
  mesh.name = path;
  mesh.stats.fileBytes = size;
  ObjParser parser(path, data, mesh, options, names);
  parser.parseLines(data, data + size);
  parser.finish();
  return mesh;
}

/// The material libraries `names` refers to, each read once, in order of first reference.
std::vector<MtlLibrary> readLibraries(const std::string& objPath, const ObjNames& names) {
  std::vector<MtlLibrary> libraries;
  for (const LibraryRef& ref : names.libraries) {
    bool seen = false;
    for (const MtlLibrary& l : libraries) seen = seen || l.path == ref.path;
    if (seen) continue;
    std::unique_ptr<MappedFile> file;
    try {
      file = std::make_unique<MappedFile>(ref.path);
    } catch (const Error& e) {
      throw Error(cat(objPath, ":", ref.line, ": mtllib '", ref.name, "': ", e.what()));
    }
    libraries.push_back(parseMtl(file->data(), file->size(), ref.path));
  }
  return libraries;
}

/// The scene file of the OBJ at `data`: one mesh placed once, its names, and its materials
/// from the libraries when LoadOptions::materials asks for them (the first definition of a name
/// wins; a map_Kd is checked, and becomes a texture, only for a material the faces use).
SceneFile objSceneFile(const char* data, size_t size, const std::string& path,
                       const LoadOptions& options) {
  SceneFile scene;
  scene.path = path;
  scene.fileBytes = size;
  ObjNames names;
  scene.meshes.push_back(parseObj(data, size, path, options, &names));
  scene.instances.push_back({0, glm::dmat4(1.0), 0});
  scene.instanceNames = std::move(names.objects);
  scene.meshNames = {fileStem(path)};
  scene.materialNames = names.materials;
  // The libraries give colours and textures, which only the material-reading AOVs (material,
  // albedo) ask for: a depth render of an OBJ whose .mtl did not come along still works.
  const std::vector<MtlLibrary> libraries =
      options.materials ? readLibraries(path, names) : std::vector<MtlLibrary>{};
  std::unordered_map<std::string, std::pair<const MtlLibrary*, const MtlMaterial*>> byName;
  for (const MtlLibrary& library : libraries)
    for (const MtlMaterial& m : library.materials) byName.emplace(m.name, std::pair{&library, &m});
  for (size_t id = 0; id < names.materials.size(); ++id) {
    Material material;
    material.name = names.materials[id];
    scene.materials.push_back(material);
    if (names.defaultMaterial && id + 1 == names.materials.size()) break;  // "default": white
    const auto found = byName.find(material.name);
    if (found == byName.end()) continue;
    const auto [library, entry] = found->second;
    scene.materials.back().baseColor = glm::vec4(entry->kd, 1.0f);
    if (entry->mapKd.empty()) continue;
    const std::string where = cat(library->path, ":", entry->mapKdLine);
    const std::string usedBy = cat(" (material '", material.name, "' used in ", path, ")");
    if (!entry->mapKdProblem.empty()) throw Error(entry->mapKdProblem + usedBy);
    std::error_code ec;
    if (!std::filesystem::is_regular_file(entry->mapKd, ec))
      throw Error(cat(
          where, ": map_Kd texture '", entry->mapKd, "' ",
          std::filesystem::exists(entry->mapKd, ec) ? "is not a regular file" : "does not exist",
          usedBy));
    SurfaceTexture texture;
    texture.where = where;
    texture.path = entry->mapKd;
    texture.wrapS = texture.wrapT = entry->wrap;
    texture.srgb = true;
    texture.nearest = false;
    scene.materials.back().baseColorTexture = int(scene.textures.size());
    scene.textures.push_back(std::move(texture));
  }
  return scene;
}

}  // namespace

Mesh loadObj(const std::string& path, const LoadOptions& options) {
  MappedFile file(path);
  return loadObjFromMemory(file.data(), file.size(), path, options);
}

Mesh loadObjFromMemory(const char* data, size_t size, const std::string& path,
                       const LoadOptions& options) {
  return parseObj(data, size, path, options, nullptr);
}

SceneFile loadObjScene(const std::string& path, const LoadOptions& options) {
  MappedFile file(path);
  return loadObjSceneFromMemory(file.data(), file.size(), path, options);
}

SceneFile loadObjSceneFromMemory(const char* data, size_t size, const std::string& path,
                                 const LoadOptions& options) {
  return objSceneFile(data, size, path, options);
}

}  // namespace aperture
