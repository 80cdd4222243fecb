// Wavefront material libraries: `newmtl NAME`, `Kd r g b` and `map_Kd [options] file`.
//
// map_Kd options: `-clamp on|off` sets the wrap mode (on: ClampToEdge; OBJ's default is
// Repeat). Options that do not change the colour looked up at a texture coordinate are
// ignored: -blendu, -blendv, -boost, -texres, -bm and -imfchan (the last two belong to bump
// and scalar maps), and `-cc off`. Options that change the mapping or the colour (-s, -o, -t,
// -mm, `-cc on`) and any unknown option are refused, naming the option: the material's texture
// cannot be sampled as the file means it.
#include "core/mesh/mtl.h"

#include <cctype>
#include <cmath>
#include <cstring>
#include <string_view>

#include "core/util/error.h"
#include "core/util/mapped_file.h"

namespace aperture {
namespace {

bool isMtlBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// The blank-separated tokens of one line, up to a '#' comment.
std::vector<std::string_view> lineTokens(const char* p, const char* end) {
  std::vector<std::string_view> tokens;
  while (true) {
    while (p < end && isMtlBlank(*p)) ++p;
    if (p == end || *p == '#') return tokens;
    const char* b = p;
    while (p < end && !isMtlBlank(*p) && *p != '#') ++p;
    tokens.emplace_back(b, size_t(p - b));
  }
}

bool equalsIgnoringCase(std::string_view a, const char* b) {
  const size_t n = std::strlen(b);
  if (a.size() != n) return false;
  for (size_t k = 0; k < n; ++k)
    if (std::tolower(static_cast<unsigned char>(a[k])) != b[k]) return false;
  return true;
}

/// The text from the start of token `first` to the end of the last token (file names with
/// blanks keep them).
std::string restOf(const std::vector<std::string_view>& tokens, size_t first) {
  if (first >= tokens.size()) return {};
  const char* b = tokens[first].data();
  const char* e = tokens.back().data() + tokens.back().size();
  return std::string(b, size_t(e - b));
}

class MtlParser {
 public:
  MtlParser(const std::string& path, MtlLibrary& library) : path_(path), library_(library) {}

  void parseLine(const char* p, const char* end) {
    const std::vector<std::string_view> tokens = lineTokens(p, end);
    if (tokens.empty()) return;
    const std::string_view key = tokens[0];
    if (key == "newmtl") {
      const std::string name = restOf(tokens, 1);
      if (name.empty()) throw Error(cat(where(), ": newmtl without a material name"));
      library_.materials.push_back({});
      library_.materials.back().name = name;
    } else if (equalsIgnoringCase(key, "kd")) {
      parseKd(tokens);
    } else if (equalsIgnoringCase(key, "map_kd")) {
      parseMapKd(tokens);
    }
  }

  size_t line = 0;

 private:
  std::string where() const { return cat(path_, ":", line); }

  MtlMaterial& current(std::string_view key) {
    if (library_.materials.empty())
      throw Error(cat(where(), ": '", std::string(key), "' before any newmtl"));
    return library_.materials.back();
  }

  /// `Kd r g b` or `Kd r`. The spectral and CIEXYZ forms are refused.
  void parseKd(const std::vector<std::string_view>& tokens) {
    MtlMaterial& m = current(tokens[0]);
    if (tokens.size() > 1 && (tokens[1] == "spectral" || tokens[1] == "xyz"))
      throw Error(cat(where(), ": 'Kd ", std::string(tokens[1]),
                      "' is not supported (Kd r g b is: linear RGB)"));
    if (tokens.size() != 2 && tokens.size() != 4)
      throw Error(cat(where(), ": Kd needs 3 numbers (r g b), got ", tokens.size() - 1));
    float rgb[3];
    for (size_t k = 1; k < tokens.size(); ++k) {
      double v;
      const char* b = tokens[k].data();
      if (!parseDoubleToken(b, b + tokens[k].size(), v) || !std::isfinite(v))
        throw Error(cat(where(), ": Kd value is not a finite number: '",
                        printableToken(b, b + tokens[k].size()), "'"));
      rgb[k - 1] = float(v);
    }
    m.kd = tokens.size() == 2 ? glm::vec3(rgb[0]) : glm::vec3(rgb[0], rgb[1], rgb[2]);
  }

  /// `map_Kd [options] file`: the options (see the top of this file), then the file name (the
  /// rest of the line).
  void parseMapKd(const std::vector<std::string_view>& tokens) {
    MtlMaterial& m = current(tokens[0]);
    m.mapKdLine = line;
    m.mapKdProblem.clear();
    m.wrap = TextureWrap::Repeat;
    size_t k = 1;
    while (k < tokens.size() && tokens[k].size() > 1 && tokens[k][0] == '-') {
      const std::string option(tokens[k]);
      const auto argument = [&](size_t i) {
        return k + i < tokens.size() ? std::string(tokens[k + i]) : std::string();
      };
      if (option == "-blendu" || option == "-blendv" || option == "-boost" || option == "-texres" ||
          option == "-bm" || option == "-imfchan") {
        k += 2;
      } else if (option == "-clamp") {
        m.wrap = argument(1) == "on" ? TextureWrap::ClampToEdge : TextureWrap::Repeat;
        k += 2;
      } else if (option == "-cc" && argument(1) != "on") {
        k += 2;
      } else {
        const bool mapping = option == "-s" || option == "-o" || option == "-t";
        m.mapKdProblem =
            cat(where(), ": map_Kd option '", option, option == "-cc" ? " on" : "",
                "' is not supported",
                mapping ? " (it scales or offsets the texture coordinates; aperture samples map_Kd "
                          "at the vertices' vt as they are)"
                        : " (aperture reads -clamp and ignores -blendu, -blendv, -boost, -texres, "
                          "-bm, -imfchan and -cc off)");
        // Skip the option's numbers so that the file name is still found.
        ++k;
        while (k + 1 < tokens.size()) {
          double v;
          const char* b = tokens[k].data();
          if (!parseDoubleToken(b, b + tokens[k].size(), v)) break;
          ++k;
        }
      }
    }
    const std::string file = restOf(tokens, k);
    if (file.empty()) throw Error(cat(where(), ": map_Kd without a file name"));
    m.mapKd = pathBeside(path_, file);
  }

  const std::string& path_;
  MtlLibrary& library_;
};

}  // namespace

std::string pathBeside(const std::string& file, const std::string& relative) {
  if (!relative.empty() && relative[0] == '/') return relative;
  const size_t slash = file.find_last_of('/');
  if (slash == std::string::npos) return relative;
  return file.substr(0, slash + 1) + relative;
}

MtlLibrary parseMtl(const char* data, size_t size, const std::string& path) {
  MtlLibrary library;
  library.path = path;
  MtlParser parser(path, library);
  const char* p = data;
  const char* end = data + size;
  while (p < end) {
    ++parser.line;
    const char* lineEnd = static_cast<const char*>(std::memchr(p, '\n', size_t(end - p)));
    if (!lineEnd) lineEnd = end;
    parser.parseLine(p, lineEnd);
    p = lineEnd + 1;
  }
  return library;
}

}  // namespace aperture
