#include "core/limits.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string_view>

#include "core/error.h"

namespace aperture {

namespace {

constexpr size_t kSampleBytes = size_t(1) << 20;

/// The first min(size, kSampleBytes) bytes of a regular file; false for anything unreadable
/// (the loader reports that with its own message).
bool readHead(const std::string& path, std::string& head, uint64_t& fileBytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
  fileBytes = uint64_t(st.st_size);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  head.resize(size_t(std::min<uint64_t>(fileBytes, kSampleBytes)));
  size_t done = 0;
  while (done < head.size()) {
    const ssize_t n = ::pread(fd, &head[done], head.size() - done, off_t(done));
    if (n <= 0) break;
    done += size_t(n);
  }
  ::close(fd);
  head.resize(done);
  return true;
}

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    size_t j = i;
    while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

size_t plyTypeSize(std::string_view t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "double" || t == "float64") return 8;
  return 4;
}

struct PlyElem {
  std::string name;
  uint64_t count = 0;
  uint64_t fixedBytes = 0;  // bytes of the scalar properties (binary)
  uint64_t minBytes = 0;    // smallest possible item (binary: scalars + list counts)
  int lists = 0, props = 0;
  size_t listCountBytes = 1, listItemBytes = 4;
  bool doubleXyz = false;
};

void estimatePly(const std::string& head, uint64_t fileBytes, MeshSizeEstimate& m) {
  std::vector<PlyElem> elems;
  bool ascii = true, terminated = false;
  size_t pos = 0;
  uint64_t headerBytes = 0;
  while (pos < head.size()) {
    size_t nl = head.find('\n', pos);
    if (nl == std::string::npos) break;
    auto w = words(std::string_view(head).substr(pos, nl - pos));
    pos = nl + 1;
    if (w.empty()) continue;
    if (w[0] == "end_header") {
      terminated = true;
      headerBytes = pos;
      break;
    }
    if (w[0] == "format" && w.size() >= 2) ascii = w[1] == "ascii";
    if (w[0] == "element" && w.size() == 3) {
      PlyElem e;
      e.name = std::string(w[1]);
      e.count = std::strtoull(std::string(w[2]).c_str(), nullptr, 10);
      elems.push_back(e);
    }
    if (w[0] == "property" && !elems.empty()) {
      PlyElem& e = elems.back();
      ++e.props;
      if (w.size() == 5 && w[1] == "list") {
        ++e.lists;
        e.listCountBytes = plyTypeSize(w[2]);
        e.listItemBytes = plyTypeSize(w[3]);
        e.minBytes += e.listCountBytes;
      } else if (w.size() == 3) {
        e.fixedBytes += plyTypeSize(w[1]);
        e.minBytes += plyTypeSize(w[1]);
        if ((w[1] == "double" || w[1] == "float64") && (w[2] == "x" || w[2] == "y" || w[2] == "z"))
          e.doubleXyz = true;
      }
    }
  }
  if (!terminated) return;
  const uint64_t dataBytes = fileBytes - headerBytes;
  // Clamp counts to what the data could hold (ASCII: at least 2 bytes a value).
  for (PlyElem& e : elems) {
    const uint64_t minItem = ascii ? 2 * uint64_t(e.props) : e.minBytes;
    if (minItem > 0) e.count = std::min(e.count, dataBytes / minItem);
  }
  bool doubles = false;
  uint64_t otherBytes = 0;
  bool othersFixed = true;
  for (const PlyElem& e : elems) {
    if (e.name == "vertex") {
      m.vertices = e.count;
      doubles = e.doubleXyz;
    }
    if (e.name != "face" && e.name != "tristrips") {
      if (e.lists) othersFixed = false;
      otherBytes += e.count * e.fixedBytes;
    }
  }
  for (const PlyElem& e : elems) {
    if (e.name == "face") {
      m.triangles += e.count;
      // Binary faces with one list and fixed-size other elements: the average polygon size
      // follows from the bytes the faces take.
      if (!ascii && othersFixed && e.lists == 1 && e.count > 0 && dataBytes > otherBytes) {
        const double perFace = double(dataBytes - otherBytes) / double(e.count);
        const double corners =
            (perFace - double(e.fixedBytes + e.listCountBytes)) / double(e.listItemBytes);
        if (corners > 3) m.triangles = e.count * uint64_t(std::lround(corners - 2));
      }
    } else if (e.name == "tristrips") {
      m.triangles += dataBytes / (ascii ? 2 : e.listItemBytes);
    }
  }
  m.loaderBytes = m.vertices * (doubles ? 37 : 13) + m.triangles * 12;
  m.how = "PLY header";
}

/// Up to 4 chunks of 256 KiB spread over the file (all of it when it is 1 MiB or less), each
/// starting at a line start, so a file with all its vertices first still shows its faces.
std::string sampleChunks(const std::string& path, uint64_t fileBytes) {
  constexpr uint64_t kChunk = kSampleBytes / 4;
  std::string out;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return out;
  const int chunks = fileBytes <= kSampleBytes ? 1 : 4;
  for (int c = 0; c < chunks; ++c) {
    const uint64_t start = chunks == 1 ? 0 : (fileBytes - kChunk) / 3 * uint64_t(c);
    std::string buf(size_t(chunks == 1 ? fileBytes : kChunk), '\0');
    const ssize_t n = ::pread(fd, &buf[0], buf.size(), off_t(start));
    if (n <= 0) break;
    buf.resize(size_t(n));
    size_t from = 0;
    if (start > 0) {
      from = buf.find('\n');
      from = from == std::string::npos ? buf.size() : from + 1;
    }
    const size_t to = buf.rfind('\n');
    if (to != std::string::npos && to >= from) out.append(buf, from, to + 1 - from);
  }
  ::close(fd);
  return out;
}

void estimateObj(const std::string& head, uint64_t fileBytes, MeshSizeEstimate& m) {
  uint64_t vertices = 0, triangles = 0;
  size_t pos = 0;
  while (pos < head.size()) {
    size_t nl = head.find('\n', pos);
    if (nl == std::string::npos) nl = head.size();
    std::string_view line(head.data() + pos, nl - pos);
    pos = nl + 1;
    if (line.size() < 2 || !std::isspace(static_cast<unsigned char>(line[1]))) continue;
    if (line[0] == 'v') {
      ++vertices;
    } else if (line[0] == 'f') {
      const size_t corners = words(line).size() - 1;
      if (corners >= 3) triangles += corners - 2;
    }
  }
  const double scale = head.empty() ? 0.0 : double(fileBytes) / double(head.size());
  m.vertices = uint64_t(std::ceil(double(vertices) * scale));
  m.triangles = uint64_t(std::ceil(double(triangles) * scale));
  // Vectors grown by push_back: up to twice their size; doubles first, then floats.
  m.loaderBytes = m.vertices * 61 + m.triangles * 24;
  m.how = cat("OBJ sample of ", head.size(), " bytes");
}

void estimateProcedural(const std::string& spec, MeshSizeEstimate& m) {
  std::string rest = spec.substr(std::strlen("procedural:"));
  const size_t q = rest.find('?');
  const std::string name = rest.substr(0, q);
  std::map<std::string, double> params;
  if (q != std::string::npos) {
    std::string query = rest.substr(q + 1);
    size_t at = 0;
    while (at <= query.size()) {
      size_t amp = query.find('&', at);
      if (amp == std::string::npos) amp = query.size();
      const std::string kv = query.substr(at, amp - at);
      const size_t eq = kv.find('=');
      if (eq != std::string::npos)
        params[kv.substr(0, eq)] = std::strtod(kv.c_str() + eq + 1, nullptr);
      at = amp + 1;
    }
  }
  auto get = [&](const char* key, double fallback) {
    auto it = params.find(key);
    const double v = it == params.end() ? fallback : it->second;
    return std::isfinite(v) && v > 0 ? std::min(v, 1e10) : fallback;
  };
  double tris = 20000;  // city
  if (name == "spheres" || name == "default") {
    tris = get("tris", 200000);
  } else if (name == "sphere") {
    tris = 2 * get("segments", 64) * get("rings", 32);
  } else if (name == "quad") {
    tris = 2;
  } else if (name == "cube") {
    tris = 12;
  }
  m.triangles = uint64_t(tris);
  m.vertices = m.triangles / 2 + 8;
  m.loaderBytes = m.vertices * 37 + m.triangles * 12;
  m.how = "procedural spec";
}

std::string lowerExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

MeshSizeEstimate estimateMeshSize(const std::string& spec) {
  MeshSizeEstimate m;
  if (spec.rfind("procedural:", 0) == 0) {
    estimateProcedural(spec, m);
    return m;
  }
  std::string head;
  if (!readHead(spec, head, m.fileBytes)) {
    m.how = "unreadable (left to the loader)";
    return m;
  }
  const std::string ext = lowerExtension(spec);
  if (ext == ".ply")
    estimatePly(head, m.fileBytes, m);
  else if (ext == ".obj")
    estimateObj(sampleChunks(spec, m.fileBytes), m.fileBytes, m);
  // The loaders map the whole file; its pages count too.
  m.loaderBytes += m.fileBytes;
  if (m.how.empty()) {
    // Unknown or unparseable: assume the loader's buffers are as large as the file.
    m.how = "file size";
  }
  return m;
}

uint64_t framebufferBytesPerPixel(AovMask aovs) {
  uint64_t b = 0;
  if (aovs & kAovColor) b += 16;
  if (aovs & kAovDepth) b += 4;
  if (aovs & kAovDistance) b += 4;
  if (aovs & kAovNormal) b += 12;
  if (aovs & kAovPosition) b += 12;
  if (aovs & kAovPrimId) b += 4;
  if (aovs & kAovGeomId) b += 4;
  return b;
}

std::string formatBytes(uint64_t bytes) {
  const double b = double(bytes);
  char buf[64];
  if (b >= 1e12)
    std::snprintf(buf, sizeof buf, "%.1f TB", b / 1e12);
  else if (b >= 1e9)
    std::snprintf(buf, sizeof buf, "%.2f GB", b / 1e9);
  else if (b >= 1e6)
    std::snprintf(buf, sizeof buf, "%.1f MB", b / 1e6);
  else if (b >= 1e3)
    std::snprintf(buf, sizeof buf, "%.1f KB", b / 1e3);
  else
    std::snprintf(buf, sizeof buf, "%llu bytes", static_cast<unsigned long long>(bytes));
  return buf;
}

std::string MemoryEstimate::describe() const {
  return cat(formatBytes(total()), " (meshes ", formatBytes(meshBytes), " for ", triangles,
             " triangles, BVH ", formatBytes(bvhBytes), ", framebuffers ",
             formatBytes(framebufferBytes), ", runtime ", formatBytes(runtimeBytes), ")");
}

MemoryEstimate estimateMemory(const std::vector<std::string>& meshSpecs, uint64_t width,
                              uint64_t height, AovMask aovs, uint64_t extraBytesPerPixel) {
  MemoryEstimate e;
  for (const std::string& spec : meshSpecs) {
    const MeshSizeEstimate m = estimateMeshSize(spec);
    e.meshBytes += m.loaderBytes;
    e.triangles += m.triangles;
  }
  e.bvhBytes = e.triangles * kBvhBytesPerTriangle;
  e.runtimeBytes = kRuntimeBytes;
  // Sizes are validated before this is called, so the product does not overflow.
  e.framebufferBytes = width * height * (framebufferBytesPerPixel(aovs) + extraBytesPerPixel);
  return e;
}

uint64_t availableMemoryBytes() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  uint64_t value = 0;
  std::string unit;
  while (in >> key >> value) {
    std::getline(in, unit);
    if (key == "MemAvailable:") return value * 1024;
  }
  throw Error("cannot read MemAvailable from /proc/meminfo (use a byte count instead of 'auto')");
}

uint64_t parseMemoryLimit(const std::string& flag, const std::string& text) {
  if (text.empty()) return 0;
  if (text == "auto") return availableMemoryBytes();
  const char* b = text.c_str();
  char* e = nullptr;
  const double v = std::strtod(b, &e);
  std::string suffix(e);
  for (char& c : suffix) c = char(std::toupper(static_cast<unsigned char>(c)));
  double scale = 0;
  if (suffix.empty() || suffix == "B")
    scale = 1;
  else if (suffix == "K" || suffix == "KB" || suffix == "KIB")
    scale = 1024.0;
  else if (suffix == "M" || suffix == "MB" || suffix == "MIB")
    scale = 1024.0 * 1024;
  else if (suffix == "G" || suffix == "GB" || suffix == "GIB")
    scale = 1024.0 * 1024 * 1024;
  else if (suffix == "T" || suffix == "TB" || suffix == "TIB")
    scale = 1024.0 * 1024 * 1024 * 1024;
  const double bytes = v * scale;
  if (e == b || scale == 0 || !std::isfinite(bytes) || bytes < 1 || bytes > 9.2e18)
    throw Error(cat(flag, ": '", text,
                    "' is not a memory size (expected BYTES with an optional "
                    "K, M, G or T suffix, or auto)"));
  return uint64_t(bytes);
}

void checkMemoryLimit(const MemoryEstimate& estimate, uint64_t limit, const std::string& flag,
                      const std::string& limitText) {
  if (limit == 0 || estimate.total() <= limit) return;
  throw Error(cat("the job needs about ", estimate.describe(), ", more than the memory limit of ",
                  formatBytes(limit), " (", flag, " ", limitText, "); nothing was loaded"));
}

}  // namespace aperture
