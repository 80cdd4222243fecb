// Validation of a glTF document before tinygltf parses it, so that every bad input is an
// Error naming the file and a JSON pointer (tinygltf's own messages name neither, and it reads
// image buffer views without checking their range).
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/mesh/gltf.h"
#include "core/util/error.h"

namespace aperture::gltf {

namespace {

using json = nlohmann::json;

const json& emptyArray() {
  static const json a = json::array();
  return a;
}
const json& emptyObject() {
  static const json o = json::object();
  return o;
}

/// The bytes a base64 data URI holds, or nullopt when it is not base64.
std::optional<size_t> dataUriBytes(const std::string& uri) {
  const size_t comma = uri.find(',');
  if (comma == std::string::npos || comma < 7 || uri.compare(comma - 7, 7, ";base64") != 0)
    return std::nullopt;
  size_t chars = 0, padding = 0;
  for (size_t i = comma + 1; i < uri.size(); ++i) {
    const char c = uri[i];
    if (c == '=') {
      ++padding;
      continue;
    }
    if (padding || !(std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '/'))
      return std::nullopt;
    ++chars;
  }
  if (padding > 2 || chars % 4 == 1) return std::nullopt;
  return chars * 3 / 4;
}

struct Checker {
  const json& doc;
  const Source& src;
  Rewrites rewrites;
  std::vector<size_t> bufferBytes;  // what each buffer holds (its byteLength once checked)
  std::vector<bool> emptyFallback;  // meshopt fallback buffers without data

  [[noreturn]] void bad(const std::string& pointer, const std::string& what) const {
    fail(src.file, pointer, what);
  }

  const json& array(const json& o, const char* key, const std::string& p) const {
    if (!o.contains(key)) return emptyArray();
    const json& a = o[key];
    if (!a.is_array()) bad(cat(p, "/", key), "expected an array");
    return a;
  }
  const json& object(const json& o, const char* key, const std::string& p) const {
    if (!o.contains(key)) return emptyObject();
    const json& a = o[key];
    if (!a.is_object()) bad(cat(p, "/", key), "expected an object");
    return a;
  }
  size_t count(const char* key) const { return array(doc, key, "").size(); }

  std::optional<int64_t> integer(const json& o, const char* key, const std::string& p,
                                 bool required = false) const {
    if (!o.contains(key)) {
      if (required) bad(p, cat("no ", key));
      return std::nullopt;
    }
    const json& v = o[key];
    if (v.is_number_integer()) return v.get<int64_t>();
    if (v.is_number_float()) {
      const double d = v.get<double>();
      if (std::floor(d) == d && std::fabs(d) < 9e15) return int64_t(d);
    }
    bad(cat(p, "/", key), cat("expected an integer, got ", v.dump()));
  }
  std::optional<double> number(const json& o, const char* key, const std::string& p,
                               bool required = false) const {
    if (!o.contains(key)) {
      if (required) bad(p, cat("no ", key));
      return std::nullopt;
    }
    const json& v = o[key];
    if (!v.is_number()) bad(cat(p, "/", key), cat("expected a number, got ", v.dump()));
    return v.get<double>();
  }
  void index(const json& o, const char* key, const std::string& p, size_t n, const char* what,
             bool required = false) const {
    const auto v = integer(o, key, p, required);
    if (v && (*v < 0 || uint64_t(*v) >= n))
      bad(cat(p, "/", key), cat(what, " ", *v, " does not exist (the file has ", n, ")"));
  }
  void element(const json& e, const std::string& p) const {
    if (!e.is_object()) bad(p, "expected an object");
  }

  void buffers() {
    const json& a = array(doc, "buffers", "");
    for (size_t b = 0; b < a.size(); ++b) {
      const std::string p = cat("/buffers/", b);
      element(a[b], p);
      const int64_t length = *integer(a[b], "byteLength", p, true);
      if (length < 1) bad(p + "/byteLength", cat("byteLength ", length, " (at least 1)"));
      const json& ext =
          object(object(a[b], "extensions", p), "EXT_meshopt_compression", p + "/extensions");
      const bool fallback = ext.value("fallback", false) == true;
      size_t have = 0;
      if (!a[b].contains("uri")) {
        if (src.glb && b == 0 && src.binChunkBytes > 0) {
          have = src.binChunkBytes;
        } else if (fallback) {
          rewrites.emptyFallbackBuffers.push_back(b);
          bufferBytes.push_back(0);
          emptyFallback.push_back(true);
          continue;
        } else {
          bad(p + "/uri", src.glb ? "no uri, and the GLB has no BIN chunk for it"
                                  : "no uri (only a .glb's first buffer may omit it)");
        }
      } else {
        if (!a[b]["uri"].is_string()) bad(p + "/uri", "expected a string");
        const std::string uri = a[b]["uri"].get<std::string>();
        if (isDataUri(uri)) {
          const auto n = dataUriBytes(uri);
          if (!n) bad(p + "/uri", "a data URI that is not base64");
          have = *n;
        } else {
          const std::string path = resolveUri(src.baseDir, uri);
          std::error_code ec;
          const auto size = std::filesystem::file_size(path, ec);
          if (ec) bad(p + "/uri", cat("cannot read '", path, "': ", ec.message()));
          have = size;
        }
      }
      if (have < uint64_t(length))
        bad(p + "/byteLength",
            cat("byteLength ", length, " but the buffer holds ", have, " bytes"));
      bufferBytes.push_back(size_t(length));
      emptyFallback.push_back(false);
    }
  }

  /// `offset` + `length` bytes must lie in buffer `buffer`.
  void inBuffer(size_t buffer, int64_t offset, int64_t length, const std::string& p) const {
    if (emptyFallback[buffer])
      bad(p + "/buffer", cat("buffer ", buffer,
                             " is a meshopt fallback without data: only compressed views may "
                             "name it"));
    const size_t have = bufferBytes[buffer];
    if (offset < 0 || uint64_t(offset) > have)
      bad(p + "/byteOffset",
          cat("byteOffset ", offset, " is past the end of buffer ", buffer, " (", have, " bytes)"));
    if (length < 0 || uint64_t(length) > have - uint64_t(offset))
      bad(p + "/byteLength", cat("bytes [", offset, ", ", offset + length,
                                 ") run past the end of buffer ", buffer, " (", have, " bytes)"));
  }

  void bufferViews() {
    const json& a = array(doc, "bufferViews", "");
    const size_t nb = bufferBytes.size();
    for (size_t v = 0; v < a.size(); ++v) {
      const std::string p = cat("/bufferViews/", v);
      element(a[v], p);
      index(a[v], "buffer", p, nb, "buffer", true);
      const int64_t buffer = *integer(a[v], "buffer", p);
      const int64_t length = *integer(a[v], "byteLength", p, true);
      const int64_t offset = integer(a[v], "byteOffset", p).value_or(0);
      if (length < 1) bad(p + "/byteLength", cat("byteLength ", length, " (at least 1)"));
      if (const auto stride = integer(a[v], "byteStride", p))
        if (*stride < 4 || *stride > 252 || *stride % 4)
          bad(p + "/byteStride", cat("byteStride ", *stride, " (4 to 252, a multiple of 4)"));
      const json& exts = object(a[v], "extensions", p);
      if (exts.contains("EXT_meshopt_compression")) {
        const std::string ep = p + "/extensions/EXT_meshopt_compression";
        const json& e = object(exts, "EXT_meshopt_compression", p + "/extensions");
        index(e, "buffer", ep, nb, "buffer", true);
        const int64_t eb = *integer(e, "buffer", ep);
        const int64_t el = *integer(e, "byteLength", ep, true);
        inBuffer(size_t(eb), integer(e, "byteOffset", ep).value_or(0), el, ep);
        const int64_t stride = *integer(e, "byteStride", ep, true);
        const int64_t n = *integer(e, "count", ep, true);
        if (stride < 1 || stride > 256)
          bad(ep + "/byteStride", cat("byteStride ", stride, " (1 to 256)"));
        if (n < 0 || n > (int64_t(1) << 32)) bad(ep + "/count", cat("count ", n, " (0 to 2^32)"));
        if (!e.contains("mode") || !e["mode"].is_string()) bad(ep + "/mode", "expected a string");
        const std::string mode = e["mode"].get<std::string>();
        if (mode != "ATTRIBUTES" && mode != "TRIANGLES" && mode != "INDICES")
          bad(ep + "/mode", cat("unknown mode '", mode, "'"));
        if (e.contains("filter")) {
          if (!e["filter"].is_string()) bad(ep + "/filter", "expected a string");
          const std::string f = e["filter"].get<std::string>();
          if (f != "NONE" && f != "OCTAHEDRAL" && f != "QUATERNION" && f != "EXPONENTIAL")
            bad(ep + "/filter", cat("unknown filter '", f, "'"));
        }
        // The view itself then names the fallback buffer, which may hold nothing.
        if (!emptyFallback[size_t(buffer)]) inBuffer(size_t(buffer), offset, length, p);
        continue;
      }
      inBuffer(size_t(buffer), offset, length, p);
    }
  }

  void accessors() {
    const json& a = array(doc, "accessors", "");
    const size_t nv = count("bufferViews");
    for (size_t k = 0; k < a.size(); ++k) {
      const std::string p = cat("/accessors/", k);
      element(a[k], p);
      index(a[k], "bufferView", p, nv, "buffer view");
      const int64_t type = *integer(a[k], "componentType", p, true);
      if (type < 5120 || type > 5126 || type == 5124)
        bad(p + "/componentType", cat("unknown componentType ", type));
      if (!a[k].contains("type") || !a[k]["type"].is_string())
        bad(p + "/type", "expected a string (SCALAR, VEC2, ...)");
      const std::string t = a[k]["type"].get<std::string>();
      if (t != "SCALAR" && t != "VEC2" && t != "VEC3" && t != "VEC4" && t != "MAT2" &&
          t != "MAT3" && t != "MAT4")
        bad(p + "/type", cat("unknown type '", t, "'"));
      const int64_t n = *integer(a[k], "count", p, true);
      if (n < 1) bad(p + "/count", cat("count ", n, " (at least 1)"));
      if (const auto o = integer(a[k], "byteOffset", p); o && *o < 0)
        bad(p + "/byteOffset", cat("byteOffset ", *o));
      if (a[k].contains("sparse")) {
        const std::string sp = p + "/sparse";
        const json& s = object(a[k], "sparse", p);
        const int64_t sn = *integer(s, "count", sp, true);
        if (sn < 1 || sn > n) bad(sp + "/count", cat("count ", sn, " outside [1, ", n, "]"));
        const json& si = object(s, "indices", sp);
        const json& sv = object(s, "values", sp);
        if (si.empty()) bad(sp, "no indices");
        if (sv.empty()) bad(sp, "no values");
        index(si, "bufferView", sp + "/indices", nv, "buffer view", true);
        index(sv, "bufferView", sp + "/values", nv, "buffer view", true);
        integer(si, "componentType", sp + "/indices", true);
      }
    }
  }

  void images() {
    const json& a = array(doc, "images", "");
    for (size_t i = 0; i < a.size(); ++i) {
      const std::string p = cat("/images/", i);
      element(a[i], p);
      index(a[i], "bufferView", p, count("bufferViews"), "buffer view");
      if (a[i].contains("bufferView") && a[i].contains("uri")) bad(p, "both uri and bufferView");
      if (!a[i].contains("bufferView") && !a[i].contains("uri"))
        bad(p, "neither uri nor bufferView");
      if (a[i].contains("bufferView")) {
        const int64_t v = *integer(a[i], "bufferView", p);
        if (doc["bufferViews"][size_t(v)].contains("extensions") &&
            doc["bufferViews"][size_t(v)]["extensions"].contains("EXT_meshopt_compression"))
          bad(p + "/bufferView", "an image in a meshopt-compressed buffer view");
        continue;
      }
      if (!a[i]["uri"].is_string()) bad(p + "/uri", "expected a string");
      const std::string uri = a[i]["uri"].get<std::string>();
      if (isDataUri(uri)) {
        if (!dataUriBytes(uri)) bad(p + "/uri", "a data URI that is not base64");
      } else {
        const std::string path = resolveUri(src.baseDir, uri);
        std::error_code ec;
        if (!std::filesystem::is_regular_file(path, ec))
          bad(p + "/uri", cat("no image file '", path, "'"));
      }
    }
  }

  void textureInfo(const json& o, const char* key, const std::string& p) const {
    if (!o.contains(key)) return;
    const std::string tp = cat(p, "/", key);
    const json& info = object(o, key, p);
    index(info, "index", tp, count("textures"), "texture", true);
    if (const auto tc = integer(info, "texCoord", tp); tc && *tc < 0)
      bad(tp + "/texCoord", cat("texCoord ", *tc));
  }

  void materialsAndTextures() const {
    const json& m = array(doc, "materials", "");
    for (size_t i = 0; i < m.size(); ++i) {
      const std::string p = cat("/materials/", i);
      element(m[i], p);
      const json& pbr = object(m[i], "pbrMetallicRoughness", p);
      textureInfo(pbr, "baseColorTexture", p + "/pbrMetallicRoughness");
      textureInfo(pbr, "metallicRoughnessTexture", p + "/pbrMetallicRoughness");
      for (const char* key : {"normalTexture", "occlusionTexture", "emissiveTexture"})
        textureInfo(m[i], key, p);
      if (pbr.contains("baseColorFactor")) {
        const json& f = pbr["baseColorFactor"];
        if (!f.is_array() || f.size() != 4 ||
            !std::all_of(f.begin(), f.end(), [](const json& x) { return x.is_number(); }))
          bad(p + "/pbrMetallicRoughness/baseColorFactor", "expected 4 numbers");
      }
    }
    const json& t = array(doc, "textures", "");
    for (size_t i = 0; i < t.size(); ++i) {
      const std::string p = cat("/textures/", i);
      element(t[i], p);
      index(t[i], "source", p, count("images"), "image");
      index(t[i], "sampler", p, count("samplers"), "sampler");
    }
    const json& s = array(doc, "samplers", "");
    for (size_t i = 0; i < s.size(); ++i) element(s[i], cat("/samplers/", i));
  }

  void meshes() {
    const json& a = array(doc, "meshes", "");
    const size_t na = count("accessors"), nm = count("materials"), nv = count("bufferViews");
    for (size_t m = 0; m < a.size(); ++m) {
      const std::string mp = cat("/meshes/", m);
      element(a[m], mp);
      if (!a[m].contains("primitives")) bad(mp, "no primitives");
      const json& prims = array(a[m], "primitives", mp);
      for (size_t p = 0; p < prims.size(); ++p) {
        const std::string pp = cat(mp, "/primitives/", p);
        element(prims[p], pp);
        const json& attrs = object(prims[p], "attributes", pp);
        for (auto it = attrs.begin(); it != attrs.end(); ++it)
          index(attrs, it.key().c_str(), pp + "/attributes", na, "accessor");
        index(prims[p], "indices", pp, na, "accessor");
        index(prims[p], "material", pp, nm, "material");
        if (const auto mode = integer(prims[p], "mode", pp); mode && (*mode < 0 || *mode > 6))
          bad(pp + "/mode", cat("unknown mode ", *mode));
        const json& exts = object(prims[p], "extensions", pp);
        if (exts.contains("KHR_draco_mesh_compression")) {
          const std::string dp = pp + "/extensions/KHR_draco_mesh_compression";
          const json& d = object(exts, "KHR_draco_mesh_compression", pp + "/extensions");
          index(d, "bufferView", dp, nv, "buffer view", true);
          const json& dattrs = object(d, "attributes", dp);
          for (auto it = dattrs.begin(); it != dattrs.end(); ++it)
            integer(dattrs, it.key().c_str(), dp + "/attributes", true);
          if (prims[p].contains("indices")) rewrites.dracoPrimitives.push_back({m, p});
        }
      }
    }
  }

  void cameras() const {
    const json& a = array(doc, "cameras", "");
    for (size_t c = 0; c < a.size(); ++c) {
      const std::string p = cat("/cameras/", c);
      element(a[c], p);
      const std::string type = a[c].value("type", std::string());
      if (type == "perspective") {
        const json& q = object(a[c], "perspective", p);
        if (q.empty()) bad(p + "/perspective", "missing");
        const double yfov = *number(q, "yfov", p + "/perspective", true);
        if (!(yfov > 0)) bad(p + "/perspective/yfov", cat("yfov ", yfov, " (must be > 0)"));
        number(q, "znear", p + "/perspective", true);
        number(q, "zfar", p + "/perspective");
        number(q, "aspectRatio", p + "/perspective");
      } else if (type == "orthographic") {
        const json& q = object(a[c], "orthographic", p);
        if (q.empty()) bad(p + "/orthographic", "missing");
        for (const char* key : {"xmag", "ymag", "znear", "zfar"})
          number(q, key, p + "/orthographic", true);
      } else {
        bad(p + "/type", "expected \"perspective\" or \"orthographic\"");
      }
    }
  }

  void nodes() const {
    const json& a = array(doc, "nodes", "");
    const size_t n = a.size();
    std::vector<int64_t> parent(n, -1);
    for (size_t k = 0; k < n; ++k) {
      const std::string p = cat("/nodes/", k);
      element(a[k], p);
      index(a[k], "mesh", p, count("meshes"), "mesh");
      index(a[k], "camera", p, count("cameras"), "camera");
      auto numbers = [&](const char* key, size_t size) {
        if (!a[k].contains(key)) return;
        const json& v = a[k][key];
        if (!v.is_array() || v.size() != size ||
            !std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); }))
          bad(cat(p, "/", key), cat("expected ", size, " numbers"));
      };
      numbers("matrix", 16);
      numbers("translation", 3);
      numbers("rotation", 4);
      numbers("scale", 3);
      const json& children = array(a[k], "children", p);
      for (size_t j = 0; j < children.size(); ++j) {
        const json& c = children[j];
        if (!c.is_number_integer() || c.get<int64_t>() < 0 || uint64_t(c.get<int64_t>()) >= n)
          bad(cat(p, "/children/", j),
              cat("node ", c.dump(), " does not exist (the file has ", n, ")"));
        const int64_t child = c.get<int64_t>();
        if (child == int64_t(k)) bad(p + "/children", cat("node ", k, " is its own child"));
        if (parent[size_t(child)] >= 0)
          bad(p + "/children", cat("node ", child, " is also a child of node ",
                                   parent[size_t(child)], " (a node has at most one parent)"));
        parent[size_t(child)] = int64_t(k);
      }
    }
    // With one parent each, a cycle is a parent chain that comes back on itself.
    std::vector<char> state(n, 0);  // 0 unseen, 1 on the current chain, 2 done
    std::vector<size_t> chain;
    for (size_t k = 0; k < n; ++k) {
      chain.clear();
      int64_t at = int64_t(k);
      while (at >= 0 && state[size_t(at)] == 0) {
        state[size_t(at)] = 1;
        chain.push_back(size_t(at));
        at = parent[size_t(at)];
      }
      if (at >= 0 && state[size_t(at)] == 1)
        bad(cat("/nodes/", parent[size_t(at)], "/children"),
            cat("node ", at, " is its own ancestor (the node graph has a cycle)"));
      for (size_t c : chain) state[c] = 2;
    }
  }

  void scenes() const {
    const json& a = array(doc, "scenes", "");
    for (size_t s = 0; s < a.size(); ++s) {
      const std::string p = cat("/scenes/", s);
      element(a[s], p);
      const json& roots = array(a[s], "nodes", p);
      for (size_t j = 0; j < roots.size(); ++j)
        if (!roots[j].is_number_integer() || roots[j].get<int64_t>() < 0 ||
            uint64_t(roots[j].get<int64_t>()) >= count("nodes"))
          bad(cat(p, "/nodes/", j),
              cat("node ", roots[j].dump(), " does not exist (the file has ", count("nodes"), ")"));
    }
    if (doc.contains("scene")) {
      const auto s = integer(doc, "scene", "");
      if (*s < 0 || uint64_t(*s) >= a.size())
        bad("/scene", cat("scene ", *s, " is out of range: the file has ", a.size(), " scenes"));
    }
  }
};

}  // namespace

Rewrites checkDocument(const nlohmann::json& doc, const Source& source) {
  if (!doc.is_object()) fail(source.file, "", "the glTF JSON is not an object");
  Checker c{doc, source, {}, {}, {}};
  const json& asset = c.object(doc, "asset", "");
  if (!asset.contains("version") || !asset["version"].is_string())
    c.bad("/asset/version", "missing (a glTF file must give its version)");
  if (asset["version"].get<std::string>().rfind("2.", 0) != 0)
    c.bad("/asset/version", cat("version ", asset["version"].dump(), " (aperture reads glTF 2.x)"));
  const json& required = c.array(doc, "extensionsRequired", "");
  for (size_t i = 0; i < required.size(); ++i)
    if (!required[i].is_string()) c.bad(cat("/extensionsRequired/", i), "expected a string");
  c.buffers();
  c.bufferViews();
  c.accessors();
  c.images();
  c.materialsAndTextures();
  c.meshes();
  c.cameras();
  c.nodes();
  c.scenes();
  return c.rewrites;
}

}  // namespace aperture::gltf
