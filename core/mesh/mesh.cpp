#include "core/mesh/mesh.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/util/error.h"
#include "core/util/huge_pages.h"
#include "core/util/parallel.h"
#include "core/util/spelling.h"
#include "core/util/vector_kernel.h"

namespace aperture {

std::string lowerExtension(const std::string& path) {
  size_t slash = path.find_last_of('/');
  size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return toLowerAscii(path.substr(dot));
}

const MeshProperty* Mesh::property(PropertyDomain domain, const std::string& propertyName) const {
  for (const MeshProperty& p : properties)
    if (p.domain == domain && p.name == propertyName) return &p;
  return nullptr;
}

void Mesh::bounds(glm::vec3& lo, glm::vec3& hi) const {
  lo = glm::vec3(std::numeric_limits<float>::max());
  hi = glm::vec3(-std::numeric_limits<float>::max());
  for (size_t k = 0; k < vertexCount; ++k) {
    glm::vec3 v = vertex(k);
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) continue;
    lo = glm::min(lo, v);
    hi = glm::max(hi, v);
  }
}

size_t meshBufferBytes(const Mesh& mesh) {
  size_t bytes = mesh.positions.capacity() * sizeof(float) +
                 mesh.indices.capacity() * sizeof(uint32_t) +
                 mesh.positionsDouble.capacity() * sizeof(double) +
                 mesh.vertexNormals.capacity() * sizeof(float) +
                 mesh.sourceTriangles.capacity() * sizeof(uint32_t) +
                 (mesh.texcoords.capacity() + mesh.vertexColors.capacity()) * sizeof(float) +
                 (mesh.faceMaterials.capacity() + mesh.faceGroups.capacity()) * sizeof(uint32_t);
  for (const MeshProperty& p : mesh.properties) bytes += p.values.capacity() * sizeof(uint32_t);
  return bytes;
}

Mesh loadUnfinishedMesh(const std::string& spec, const LoadOptions& options) {
  if (spec.rfind("procedural:", 0) == 0) {
    if (!options.properties.empty())
      throw Error(cat(spec, ": AOV '", options.properties.front().aovName(),
                      "': a procedural mesh has no integer face or vertex properties (PLY "
                      "files do)"));
    return makeProcedural(spec);  // no vertex normals: shading normals fall back to Ng
  }
  const std::string ext = lowerExtension(spec);
  if (ext == ".ply") return loadPly(spec, options);
  if (ext == ".obj") return loadObj(spec, options);
  if (ext == ".gltf" || ext == ".glb")
    throw Error(cat(spec, ": a glTF file holds a scene of meshes: load it with loadSceneFile"));
  throw Error(cat(spec, ": unknown mesh file extension '", ext,
                  "' (expected .ply, .obj, .gltf, .glb or procedural:NAME)"));
}

Mesh loadMesh(const std::string& spec, const LoadOptions& options) {
  auto start = std::chrono::steady_clock::now();
  Mesh mesh = loadUnfinishedMesh(spec, options);
  finishMesh(mesh, options);
  mesh.stats.loadSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return mesh;
}

namespace {

/// The loader's vertices after the options' scale, translate and transform, in double; reads
/// the loader's float or double positions as they are at the time of the call.
class WorldVertices {
 public:
  WorldVertices(const Mesh& mesh, const LoadOptions& options, bool fromDouble)
      : mesh_(mesh), options_(options), fromDouble_(fromDouble) {}

  /// Float positions placed without a transform: world coordinate a of vertex k is
  /// scale * positions[3k + a] + translate[a], which the loops below compute directly.
  bool plain() const { return !fromDouble_ && !options_.transform; }
  const float* plainPositions() const { return mesh_.positions.data(); }
  double plainScale() const { return options_.scale; }
  glm::dvec3 plainTranslate() const { return options_.translate; }

  glm::dvec3 operator()(size_t k) const {
    const glm::dvec3 v =
        options_.scale * glm::dvec3(coord(3 * k), coord(3 * k + 1), coord(3 * k + 2)) +
        options_.translate;
    return options_.transform ? glm::dvec3(*options_.transform * glm::dvec4(v, 1.0)) : v;
  }

 private:
  double coord(size_t i) const {
    return fromDouble_ ? mesh_.positionsDouble[i] : double(mesh_.positions[i]);
  }

  const Mesh& mesh_;
  const LoadOptions& options_;
  bool fromDouble_;
};

/// Items per chunk of finishMesh's parallel passes.
constexpr size_t kItemsPerChunk = size_t(1) << 16;

size_t chunkCount(size_t n) { return (n + kItemsPerChunk - 1) / kItemsPerChunk; }

/// Calls body(c, begin, end) in parallel for chunk c = [c, c + 1) * kItemsPerChunk of [0, n)
/// (parallelForChunks: numbered chunks, so per-chunk results can be combined in order and give
/// exactly what one serial pass gives, whatever the thread count).
template <class Body>
void forEachChunk(size_t n, const Body& body) {
  parallelForChunks(n, kItemsPerChunk, body);
}

/// What one pass over a mesh's indices finds.
struct IndexScan {
  size_t outOfRange = 0;       ///< indices >= vertexCount
  size_t firstOutOfRange = 0;  ///< position in mesh.indices of the first of them
  size_t degenerate = 0;       ///< triangles that repeat an index
};

/// Counts, over the `triangles` triangles at `indices`, the indices >= n and the triangles
/// that repeat an index: comparisons without branches, which the loop vectoriser takes.
void countBadIndices(const uint32_t* indices, size_t triangles, uint64_t n, IndexScan& scan) {
  size_t outOfRange = 0, degenerate = 0;
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t a = indices[3 * t], b = indices[3 * t + 1], c = indices[3 * t + 2];
    outOfRange += size_t(a >= n) + size_t(b >= n) + size_t(c >= n);
    degenerate += size_t((a == b) | (b == c) | (a == c));
  }
  scan.outOfRange = outOfRange;
  scan.degenerate = degenerate;
}

/// Reads every index once, in parallel: the out-of-range ones and the degenerate triangles.
/// A chunk with an index out of range (a file the load then rejects) finds the first one again.
IndexScan scanIndices(const Mesh& mesh) {
  const size_t n = mesh.vertexCount;
  const size_t triangles = mesh.indices.size() / 3;
  std::vector<IndexScan> chunks(chunkCount(triangles));
  forEachChunk(triangles, [&](size_t c, size_t b, size_t e) {
    IndexScan s;
    runKernel<&countBadIndices>(mesh.indices.data() + 3 * b, e - b, n, s);
    if (s.outOfRange)
      s.firstOutOfRange = size_t(std::find_if(mesh.indices.begin() + ptrdiff_t(3 * b),
                                              mesh.indices.begin() + ptrdiff_t(3 * e),
                                              [&](uint32_t v) { return v >= n; }) -
                                 mesh.indices.begin());
    chunks[c] = s;
  });
  IndexScan all;
  for (const IndexScan& s : chunks) {
    if (s.outOfRange && all.outOfRange == 0) all.firstOutOfRange = s.firstOutOfRange;
    all.outOfRange += s.outOfRange;
    all.degenerate += s.degenerate;
  }
  return all;
}

/// Throws Error naming the mesh, how many indices are >= vertexCount and the first of them.
void checkIndicesInRange(const Mesh& mesh, const IndexScan& scan) {
  if (scan.outOfRange == 0) return;
  throw Error(cat(mesh.name, ": ", scan.outOfRange, " vertex indices out of range (the mesh has ",
                  mesh.vertexCount, " vertices); the first is ", mesh.indices[scan.firstOutOfRange],
                  " in triangle ", scan.firstOutOfRange / 3));
}

/// The bounding box of a chunk's finite vertices, and how many are not finite.
struct Box {
  glm::dvec3 lo{std::numeric_limits<double>::max()};
  glm::dvec3 hi{-std::numeric_limits<double>::max()};
  size_t nonFinite = 0;
};

/// The box of world vertices [b, e) of a plain placement (WorldVertices::plain), without the
/// per-vertex tests, on x86-64; false when a coordinate is not finite (or without SSE2), and
/// the per-vertex pass, which leaves non-finite vertices out, decides. Otherwise the box is
/// the one that pass finds: the same comparisons of the same values in the same order (so
/// even a zero bound's sign is the same). minpd(v, lo) is exactly v < lo ? v : lo (lo when
/// they are equal or unordered), and maxpd likewise, with x and y side by side; GCC compiles
/// the scalar form to compares and integer moves instead, at twice the time.
bool plainChunkBox(const WorldVertices& world, size_t b, size_t e, Box& box) {
#if defined(__SSE2__)
  const float* p = world.plainPositions();
  const __m128d scale = _mm_set1_pd(world.plainScale());
  const glm::dvec3 t = world.plainTranslate();
  const __m128d tXY = _mm_set_pd(t.y, t.x), tZ = _mm_set_sd(t.z);
  __m128d loXY = _mm_set_pd(box.lo.y, box.lo.x), hiXY = _mm_set_pd(box.hi.y, box.hi.x);
  __m128d loZ = _mm_set_sd(box.lo.z), hiZ = _mm_set_sd(box.hi.z);
  __m128d poisonXY = _mm_setzero_pd(), poisonZ = _mm_setzero_pd();
  for (size_t k = b; k < e; ++k) {
    const float* v = p + 3 * k;
    const __m128 xyFloat = _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(v)));
    const __m128d xy = _mm_add_pd(_mm_mul_pd(scale, _mm_cvtps_pd(xyFloat)), tXY);
    const __m128d z =
        _mm_add_sd(_mm_mul_sd(scale, _mm_cvtss_sd(_mm_setzero_pd(), _mm_load_ss(v + 2))), tZ);
    loXY = _mm_min_pd(xy, loXY);
    hiXY = _mm_max_pd(xy, hiXY);
    loZ = _mm_min_sd(z, loZ);
    hiZ = _mm_max_sd(z, hiZ);
    poisonXY = _mm_add_pd(poisonXY, _mm_sub_pd(xy, xy));
    poisonZ = _mm_add_sd(poisonZ, _mm_sub_sd(z, z));
  }
  double lo[3], hi[3], poison[3];
  _mm_storeu_pd(lo, loXY), _mm_store_sd(lo + 2, loZ);
  _mm_storeu_pd(hi, hiXY), _mm_store_sd(hi + 2, hiZ);
  _mm_storeu_pd(poison, poisonXY), _mm_store_sd(poison + 2, poisonZ);
  if (!(poison[0] == 0.0 && poison[1] == 0.0 && poison[2] == 0.0)) return false;
  box.lo = {lo[0], lo[1], lo[2]};
  box.hi = {hi[0], hi[1], hi[2]};
  return true;
#else
  (void)world, (void)b, (void)e, (void)box;
  return false;
#endif
}

/// Sets bad[k] for the n vertices with a non-finite world position and returns how many there
/// are; [lo, hi] becomes the bounding box of the others. Chunks are combined in order with
/// the same glm::min/max, so even the sign of a zero bound is that of one serial pass.
size_t markNonFiniteVertices(const WorldVertices& world, size_t n, std::vector<uint8_t>& bad,
                             glm::dvec3& lo, glm::dvec3& hi) {
  std::vector<Box> chunks(chunkCount(n));
  forEachChunk(n, [&](size_t c, size_t b, size_t e) {
    Box box;
    if (world.plain() && plainChunkBox(world, b, e, box)) {
      chunks[c] = box;
      return;
    }
    for (size_t k = b; k < e; ++k) {
      glm::dvec3 v = world(k);
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
        bad[k] = 1;
        ++box.nonFinite;
      } else {
        box.lo = glm::min(box.lo, v);
        box.hi = glm::max(box.hi, v);
      }
    }
    chunks[c] = box;
  });
  Box all;
  for (const Box& box : chunks) {
    all.lo = glm::min(all.lo, box.lo);
    all.hi = glm::max(all.hi, box.hi);
    all.nonFinite += box.nonFinite;
  }
  lo = all.lo;
  hi = all.hi;
  return all.nonFinite;
}

/// Drops the triangles using a bad vertex (when `anyBad`), with their face property values,
/// and counts, but keeps, degenerate ones (a repeated index); both counts go to the mesh's
/// stats. `scan` counted the degenerate triangles before anything was dropped.
void dropTrianglesOfBadVertices(Mesh& mesh, const std::vector<uint8_t>& bad, bool anyBad,
                                const IndexScan& scan) {
  if (!anyBad) {
    mesh.stats.droppedTriangles = 0;
    mesh.stats.degenerateTriangles = scan.degenerate;
    return;
  }
  size_t out = 0, dropped = 0, degenerate = 0;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    if (anyBad && (bad[a] || bad[b] || bad[c])) {
      ++dropped;
      continue;
    }
    if (a == b || b == c || a == c) ++degenerate;
    forEachFaceArray(mesh, [&](std::vector<uint32_t>& values) { values[out / 3] = values[t / 3]; });
    mesh.indices[out++] = a;
    mesh.indices[out++] = b;
    mesh.indices[out++] = c;
  }
  mesh.indices.resize(out);
  forEachFaceArray(mesh, [&](std::vector<uint32_t>& values) { values.resize(out / 3); });
  mesh.stats.droppedTriangles = dropped;
  mesh.stats.degenerateTriangles = degenerate;
}

/// The arithmetic of a plain placement (WorldVertices::plain) relative to an anchor, laid out
/// for four vertices (twelve floats) at a time: coordinate j of such a block becomes
/// float((scale * double(x) + translate[j]) - anchor[j]), with translate and anchor repeated
/// per vertex: the operations of WorldVertices, in the same order.
struct PlainPlacement {
  static constexpr size_t kBlock = 12;
  double scale;
  double translate[kBlock], anchor[kBlock];
  PlainPlacement(const WorldVertices& world, const glm::dvec3& anchorOf)
      : scale(world.plainScale()) {
    const glm::dvec3 t = world.plainTranslate();
    for (size_t j = 0; j < kBlock; ++j) {
      translate[j] = t[int(j % 3)];
      anchor[j] = anchorOf[int(j % 3)];
    }
  }
  /// Coordinate x at slot j of a block (or axis j of a vertex: the first three slots).
  float placed(float x, size_t j) const {
    return float((scale * double(x) + translate[j]) - anchor[j]);
  }
};

/// Rewrites the `count` vertices at `xyz` in place, placed and anchored by `p`: whole blocks of
/// four vertices with a twelve-wide inner loop that the loop vectoriser takes, then the rest.
void placePlainVertices(const PlainPlacement& p, float* xyz, size_t count) {
  constexpr size_t kBlock = PlainPlacement::kBlock;
  const size_t floats = 3 * count, whole = floats - floats % kBlock;
  for (size_t i = 0; i < whole; i += kBlock) {
    float* block = xyz + i;
    APERTURE_LANE_LOOP
    for (size_t j = 0; j < kBlock; ++j) block[j] = p.placed(block[j], j);
  }
  for (size_t i = whole; i < floats; ++i) xyz[i] = p.placed(xyz[i], i % 3);
}

/// Writes the float positions relative to mesh.anchor, padded for Embree. Non-finite vertices
/// are stored as 0 (no triangle uses them). Float sources are rewritten in place: vertex k is
/// read before it is overwritten.
void writeAnchoredPositions(Mesh& mesh, const WorldVertices& world, const std::vector<uint8_t>& bad,
                            bool anyBad, bool fromDouble) {
  const size_t n = mesh.vertexCount;
  if (fromDouble) mesh.positions.clear();  // every float is rewritten: nothing to keep
  resizeOnHugePages(mesh.positions, 3 * n + kVertexPaddingFloats);
  std::fill(mesh.positions.begin() + 3 * n, mesh.positions.end(), 0.0f);
  const bool plain = world.plain() && !anyBad;
  const PlainPlacement placement(world, mesh.anchor);
  forEachChunk(n, [&](size_t, size_t b, size_t e) {
    if (plain) {  // the same arithmetic, without the per-vertex tests
      runKernel<&placePlainVertices>(placement, mesh.positions.data() + 3 * b, e - b);
      return;
    }
    for (size_t k = b; k < e; ++k) {
      glm::dvec3 v = bad[k] ? glm::dvec3(0.0) : world(k) - mesh.anchor;
      for (int a = 0; a < 3; ++a) mesh.positions[3 * k + a] = float(v[a]);
    }
  });
}

/// Moves the vertex normals into the placed mesh's space: n' = M^-T n with M the linear part
/// of the options' placement (scale, then the transform's 3x3). The true inverse transpose,
/// not the cofactor matrix: the cofactor (det M · M^-T) would turn normals inside out under a
/// mirroring placement. Not normalised (the frame loop normalises after interpolating).
void transformVertexNormals(Mesh& mesh, const LoadOptions& options) {
  if (mesh.vertexNormals.empty()) return;
  glm::dmat3 linear = glm::dmat3(options.scale);
  if (options.transform) linear = glm::dmat3(*options.transform) * linear;
  if (linear == glm::dmat3(1.0)) return;
  const glm::dmat3 normalFrom = glm::transpose(glm::inverse(linear));
  forEachChunk(mesh.vertexNormals.size() / 3, [&](size_t, size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) {
      float* n = &mesh.vertexNormals[3 * k];
      const glm::dvec3 m = normalFrom * glm::dvec3(n[0], n[1], n[2]);
      for (int a = 0; a < 3; ++a) n[a] = float(m[a]);
    }
  });
}

/// Throws Error naming the mesh when a property has the wrong number of values.
void checkPropertySizes(const Mesh& mesh) {
  for (const MeshProperty& p : mesh.properties) {
    const bool face = p.domain == PropertyDomain::Face;
    const size_t want = face ? mesh.triangleCount() : mesh.vertexCount;
    if (p.values.size() != want)
      throw Error(cat(mesh.name, ": property '", PropertyAov{p.domain, p.name}.aovName(), "' has ",
                      p.values.size(), " values for ", want, face ? " triangles" : " vertices"));
  }
  const auto checkPerVertex = [&](const std::vector<float>& values, size_t per, const char* what) {
    if (!values.empty() && values.size() != per * mesh.vertexCount)
      throw Error(cat(mesh.name, ": ", values.size() / per, " ", what, " for ", mesh.vertexCount,
                      " vertices"));
  };
  checkPerVertex(mesh.vertexNormals, 3, "vertex normals");
  checkPerVertex(mesh.texcoords, 2, "texture coordinates");
  checkPerVertex(mesh.vertexColors, 4, "vertex colours");
  const auto checkPerFace = [&](const std::vector<uint32_t>& values, const char* what) {
    if (!values.empty() && values.size() != mesh.triangleCount())
      throw Error(cat(mesh.name, ": ", values.size(), " ", what, " for ", mesh.triangleCount(),
                      " triangles"));
  };
  checkPerFace(mesh.faceMaterials, "face materials");
  checkPerFace(mesh.faceGroups, "face groups");
}

}  // namespace

void finishMesh(Mesh& mesh, const LoadOptions& options) {
  const size_t n = mesh.vertexCount;
  const bool fromDouble = !mesh.positionsDouble.empty() || mesh.positions.empty();
  if (fromDouble) {
    APERTURE_CHECK_OP(mesh.positionsDouble.size(), ==, 3 * n);
  } else {
    APERTURE_CHECK_OP(mesh.positions.size(), >=, 3 * n);
  }
  APERTURE_CHECK_OP(mesh.indices.size() % 3, ==, 0u);
  // Index range check before anything else touches the vertices.
  const IndexScan scan = scanIndices(mesh);
  checkIndicesInRange(mesh, scan);
  checkPropertySizes(mesh);

  const WorldVertices world(mesh, options, fromDouble);
  std::vector<uint8_t> bad(n, 0);
  glm::dvec3 lo, hi;
  const size_t nonFinite = markNonFiniteVertices(world, n, bad, lo, hi);
  mesh.stats.nonFiniteVertices = nonFinite;
  dropTrianglesOfBadVertices(mesh, bad, nonFinite > 0, scan);

  if (options.placement == Placement::WorldSpace || nonFinite == n)
    mesh.anchor = glm::dvec3(0.0);
  else
    mesh.anchor = 0.5 * (lo + hi);
  writeAnchoredPositions(mesh, world, bad, nonFinite > 0, fromDouble);
  transformVertexNormals(mesh, options);
  mesh.positionsDouble.clear();
  mesh.positionsDouble.shrink_to_fit();
  // Embree shares these buffers for the scene's life: keep exactly what it reads (loaders that
  // grew them by push_back leave up to half of them unused).
  mesh.positions.shrink_to_fit();
  mesh.indices.shrink_to_fit();
}

}  // namespace aperture
