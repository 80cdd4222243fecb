#include "apps/services/limits.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>

#include "core/aov/aov_table.h"
#include "core/mesh/mesh.h"
#include "core/mesh/ply.h"
#include "core/mesh/scene_file.h"
#include "core/util/error.h"

namespace aperture {

namespace {

constexpr size_t kSampleBytes = size_t(1) << 20;

/// What finishMesh leaves for Embree (meshBufferBytes): 3 floats a vertex and the padding,
/// 3 indices a triangle.
uint64_t keptMeshBytes(uint64_t vertices, uint64_t triangles) {
  return (3 * vertices + kVertexPaddingFloats) * sizeof(float) + 3 * triangles * sizeof(uint32_t);
}

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

/// Counts a file could not hold are clamped to what its data could (the loader reports them).
void clampCountsToData(PlyHeader& h, uint64_t dataBytes) {
  for (PlyElement& e : h.elements) {
    const uint64_t minItem = plyMinItemBytes(h.format, e);
    if (minItem > 0) e.count = std::min(e.count, dataBytes / minItem);
  }
}

bool hasList(const PlyElement& e) {
  return std::any_of(e.props.begin(), e.props.end(), [](const PlyProperty& p) { return p.list; });
}

/// Binary bytes of an item's scalar properties.
uint64_t scalarBytes(const PlyElement& e) {
  uint64_t bytes = 0;
  for (const PlyProperty& p : e.props)
    if (!p.list) bytes += plyTypeSize(p.type);
  return bytes;
}

/// The list property of `e` when it has exactly one, else nullptr.
const PlyProperty* onlyList(const PlyElement& e) {
  const PlyProperty* list = nullptr;
  for (const PlyProperty& p : e.props)
    if (p.list) {
      if (list) return nullptr;
      list = &p;
    }
  return list;
}

/// How many values the lists of `e` hold in all, when the file size tells: a binary file in
/// which `e` has the only list property and every other item has a fixed size.
std::optional<uint64_t> listValueCount(const PlyHeader& h, const PlyElement& e,
                                       uint64_t dataBytes) {
  const PlyProperty* list = onlyList(e);
  if (h.format == PlyFormat::Ascii || !list) return std::nullopt;
  uint64_t otherBytes = 0;
  for (const PlyElement& other : h.elements) {
    if (&other == &e) continue;
    if (hasList(other)) return std::nullopt;
    otherBytes += other.count * scalarBytes(other);
  }
  const uint64_t ownBytes = e.count * (scalarBytes(e) + plyTypeSize(list->countType));
  if (otherBytes + ownBytes > dataBytes) return std::nullopt;
  return (dataBytes - otherBytes - ownBytes) / plyTypeSize(list->type);
}

/// Triangles the loader makes of a face element: a polygon of n corners makes n - 2 (a fan),
/// so all of them make corners - 2 * faces. One a face where the corners cannot be told.
uint64_t faceTriangles(const PlyHeader& h, const PlyElement& e, uint64_t dataBytes) {
  const std::optional<uint64_t> corners = listValueCount(h, e, dataBytes);
  return corners && *corners >= 3 * e.count ? *corners - 2 * e.count : e.count;
}

/// Triangles the loader makes of a tristrips element, bounded from above: a strip of n indices
/// makes at most n - 2 (each restart makes fewer, and only the data shows them).
uint64_t stripTriangles(const PlyHeader& h, const PlyElement& e, uint64_t dataBytes) {
  if (const std::optional<uint64_t> indices = listValueCount(h, e, dataBytes))
    return *indices > 2 * e.count ? *indices - 2 * e.count : 0;
  const PlyProperty* list = onlyList(e);
  const uint64_t bytesPerIndex = h.format == PlyFormat::Ascii ? 2
                                 : list                       ? plyTypeSize(list->type)
                                                              : 4;
  return dataBytes / bytesPerIndex;
}

bool hasDoubleCoordinates(const PlyElement& vertex) {
  return std::any_of(vertex.props.begin(), vertex.props.end(), [](const PlyProperty& p) {
    return !p.list && p.type == PlyType::Float64 &&
           (p.name == "x" || p.name == "y" || p.name == "z");
  });
}

/// Counts from the loader's own header reader; a header it rejects is left to the loader
/// (the estimate then falls back on the file size).
void estimatePly(const std::string& path, const std::string& head, uint64_t fileBytes,
                 MeshSizeEstimate& m) {
  PlyHeader h;
  try {
    h = readPlyHeader(path, head.data(), head.size());
  } catch (const Error&) {
    return;
  }
  const uint64_t dataBytes = fileBytes - std::min<uint64_t>(fileBytes, h.dataOffset);
  clampCountsToData(h, dataBytes);
  bool doubles = false;
  for (const PlyElement& e : h.elements) {
    if (e.name == "vertex") {
      m.vertices = e.count;
      doubles = hasDoubleCoordinates(e);
    } else if (e.name == "face") {
      m.triangles += faceTriangles(h, e, dataBytes);
    } else if (e.name == "tristrips") {
      m.triangles += stripTriangles(h, e, dataBytes);
    }
  }
  m.loaderBytes = m.vertices * (doubles ? 37 : 13) + m.triangles * 12;
  m.meshBytes = keptMeshBytes(m.vertices, m.triangles);
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
  m.meshBytes = keptMeshBytes(m.vertices, m.triangles);
  m.how = cat("OBJ sample of ", head.size(), " bytes");
}

/// The JSON of a glTF file: a .gltf is JSON throughout; a .glb's first chunk is (12-byte
/// header, then the chunk's length and type "JSON"). Empty when neither can be read.
std::string gltfJson(const std::string& path, uint64_t fileBytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  if (lowerExtension(path) == ".gltf") {
    if (fileBytes > (uint64_t(256) << 20)) return {};  // not a plausible scene description
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  unsigned char head[20];
  if (!in.read(reinterpret_cast<char*>(head), sizeof head)) return {};
  const auto u32 = [&](int at) {
    return uint32_t(head[at]) | uint32_t(head[at + 1]) << 8 | uint32_t(head[at + 2]) << 16 |
           uint32_t(head[at + 3]) << 24;
  };
  const uint32_t length = u32(12);
  if (u32(0) != 0x46546C67u || u32(16) != 0x4E4F534Au || 20 + uint64_t(length) > fileBytes)
    return {};
  std::string json(length, '\0');
  if (!in.read(&json[0], length)) return {};
  return json;
}

/// The counts a glTF file declares, from its JSON alone (no buffer is read): each mesh once
/// (a mesh several nodes place is stored and built once), each triangle primitive's vertices
/// (its POSITION accessor's count) and triangles (its indices' count, else its vertices', / 3
/// for mode 4, - 2 for strips and fans), Draco and meshopt primitives by the counts their
/// accessors declare; buffers the file refers to beside it (.bin) by their byteLength. A JSON
/// the loader would refuse is left to it (the estimate falls back on the file size).
void estimateGltf(const std::string& path, uint64_t fileBytes, MeshSizeEstimate& m) {
  using nlohmann::json;
  uint64_t vertices = 0, triangles = 0, externalBytes = 0;
  try {
    const json j = json::parse(gltfJson(path, fileBytes));
    const json& accessors = j.at("accessors");
    const auto count = [&](const json& index) -> uint64_t {
      return accessors.at(index.get<size_t>()).at("count").get<uint64_t>();
    };
    for (const json& mesh : j.value("meshes", json::array()))
      for (const json& p : mesh.at("primitives")) {
        const int mode = p.value("mode", 4);
        if (mode < 4) continue;  // points and lines are skipped
        const uint64_t v = count(p.at("attributes").at("POSITION"));
        const uint64_t corners = p.contains("indices") ? count(p.at("indices")) : v;
        vertices += v;
        triangles += mode == 4 ? corners / 3 : corners > 2 ? corners - 2 : 0;
      }
    for (const json& b : j.value("buffers", json::array()))
      if (b.contains("uri") && b.at("uri").get<std::string>().rfind("data:", 0) != 0)
        externalBytes += b.at("byteLength").get<uint64_t>();
  } catch (const std::exception&) {
    return;
  }
  m.vertices = vertices;
  m.triangles = triangles;
  m.meshBytes = keptMeshBytes(m.vertices, m.triangles);
  // The file and its external buffers are held while the meshes are decoded beside them;
  // then each mesh's buffers as the PLY loader's (float positions, indices, a flag a vertex).
  m.loaderBytes = externalBytes + m.meshBytes + m.vertices;
  m.how = "glTF JSON";
}

/// The generator's own counts; a spec it rejects is left to it (the estimate counts nothing).
void estimateProcedural(const std::string& spec, MeshSizeEstimate& m) {
  MeshCounts counts;
  try {
    counts = proceduralMeshCounts(spec);
  } catch (const Error&) {
    m.how = "procedural spec (invalid: left to the generator)";
    return;
  }
  m.vertices = counts.vertices;
  m.triangles = counts.triangles;
  // The generator writes double positions (24 bytes a vertex) and the indices; finishMesh adds
  // the padded float positions and a flag byte per vertex before it frees the doubles.
  m.meshBytes = keptMeshBytes(m.vertices, m.triangles);
  m.loaderBytes = m.meshBytes + m.vertices * (24 + 1);
  m.how = "procedural spec";
  m.spatiallyOrdered = true;
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
    estimatePly(spec, head, m.fileBytes, m);
  else if (ext == ".obj")
    estimateObj(sampleChunks(spec, m.fileBytes), m.fileBytes, m);
  else if (isGltfPath(spec))
    estimateGltf(spec, m.fileBytes, m);
  // The loaders map the whole file; its pages count too.
  m.loaderBytes += m.fileBytes;
  if (m.how.empty()) {
    // Unknown or unparseable: assume the loader's buffers are as large as the file.
    m.how = "file size";
    m.meshBytes = m.fileBytes;
  }
  return m;
}

uint64_t framebufferBytesPerPixel(const AovSet& set) {
  uint64_t b = 0;
  for (const AovRow& row : aovTable())
    if (set.mask & row.bit) b += 4 * uint64_t(row.channels());  // float32 or uint32 values
  b += 4 * set.properties.size();
  for (const AovRow& row : aovTable())
    if (row.layered()) b += 4 * uint64_t(set.layers);  // one float32 or uint32 per layer
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

uint64_t MemoryEstimate::total() const {
  return runtimeBytes + imageCodecBytes + lensTableBytes +
         std::max({loadPeakBytes, buildPhaseBytes(), renderPhaseBytes()});
}

std::string MemoryEstimate::describe() const {
  return cat(formatBytes(total()), " (meshes ", formatBytes(meshBytes), " for ", triangles,
             " triangles, loading peak ", formatBytes(loadPeakBytes), ", BVH ",
             formatBytes(bvhBytes), " (", formatBytes(bvhBuildBytes),
             " while building), framebuffers ", formatBytes(framebufferBytes), ", runtime ",
             formatBytes(runtimeBytes),
             imageCodecBytes ? cat(", image codec ", formatBytes(imageCodecBytes)) : "",
             lensTableBytes ? cat(", lens direction tables ", formatBytes(lensTableBytes)) : "",
             "; the peak is the runtime", lensTableBytes ? " and the tables" : "",
             " and the largest of loading, building and rendering)");
}

MemoryEstimate estimateMemory(const std::vector<std::string>& meshSpecs, uint64_t width,
                              uint64_t height, const AovSet& aovs, uint64_t extraBytesPerPixel,
                              const BuildOptions& build) {
  MemoryEstimate e;
  const uint64_t chunk = build.effectiveChunkTriangles();
  const uint64_t bvh = build.compact ? kCompactBvhBytesPerTriangle : kBvhBytesPerTriangle;
  const uint64_t building =
      build.compact ? kCompactBvhBuildBytesPerTriangle : kBvhBuildBytesPerTriangle;
  // Embree's bytes as Scene builds: each chunk of a chunked mesh in turn, beside the BVHs
  // built before it (Scene::attachChunks), then the top-level BVH of the other triangles.
  uint64_t resident = 0;
  const auto buildOf = [&](uint64_t triangles) {
    e.bvhBuildBytes = std::max(e.bvhBuildBytes, resident + building * triangles);
    resident += bvh * triangles;
  };
  uint64_t wholeTriangles = 0;  // in the top-level BVH, built in one go
  for (const std::string& spec : meshSpecs) {
    const MeshSizeEstimate m = estimateMeshSize(spec);
    // Meshes load one after the other: the ones before are kept while this one loads.
    e.loadPeakBytes = std::max(e.loadPeakBytes, e.meshBytes + m.loaderBytes);
    e.meshBytes += m.meshBytes;
    e.triangles += m.triangles;
    if (chunk > 0 && m.triangles > chunk) {
      for (uint64_t first = 0; first < m.triangles; first += chunk)
        buildOf(std::min(chunk, m.triangles - first));
      // Unless known to be in order, it may be put in spatial order: Mesh::sourceTriangles.
      if (!m.spatiallyOrdered) e.meshBytes += sizeof(uint32_t) * m.triangles;
    } else {
      wholeTriangles += m.triangles;
    }
  }
  buildOf(wholeTriangles);
  e.bvhBytes = resident;
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
