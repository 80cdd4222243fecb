// libFuzzer target: the PLY loader and finishMesh on arbitrary bytes, both as the renderer
// loads positions only and with the mesh data AOVs ask for (integer face and vertex
// properties, vertex normals), which take the general reader. Each input is loaded by the
// parallel binary readers and by the serial ones: a different mesh or message is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/ply.h"
#include "core/util/error.h"

namespace {

/// What one load and finishMesh gave: the error message, or the mesh's buffers.
struct Outcome {
  std::string error;
  aperture::Mesh mesh;
};

Outcome loadAndFinish(const uint8_t* data, size_t size, const aperture::LoadOptions& options,
                      aperture::PlyParsing parsing) {
  Outcome out;
  try {
    out.mesh = aperture::loadPlyFromMemory(reinterpret_cast<const char*>(data), size, "fuzz.ply",
                                           options, parsing);
    aperture::finishMesh(out.mesh, options);
  } catch (const aperture::Error& e) {
    // A clear error is the right answer to a malformed file.
    out.error = e.what();
  }
  return out;
}

template <class T, class Allocator>
bool sameBits(const std::vector<T, Allocator>& a, const std::vector<T, Allocator>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool sameOutcome(const Outcome& a, const Outcome& b) {
  if (a.error != b.error) return false;
  if (!sameBits(a.mesh.positions, b.mesh.positions) || !sameBits(a.mesh.indices, b.mesh.indices) ||
      !sameBits(a.mesh.vertexNormals, b.mesh.vertexNormals) ||
      a.mesh.properties.size() != b.mesh.properties.size())
    return false;
  for (size_t k = 0; k < a.mesh.properties.size(); ++k)
    if (!sameBits(a.mesh.properties[k].values, b.mesh.properties[k].values)) return false;
  return a.mesh.stats.sourceFaces == b.mesh.stats.sourceFaces &&
         std::memcmp(&a.mesh.anchor, &b.mesh.anchor, sizeof a.mesh.anchor) == 0;
}

void loadBothWays(const uint8_t* data, size_t size, const aperture::LoadOptions& options) {
  const Outcome parallel = loadAndFinish(data, size, options, aperture::PlyParsing::Parallel);
  const Outcome serial = loadAndFinish(data, size, options, aperture::PlyParsing::Serial);
  if (!sameOutcome(parallel, serial)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  loadBothWays(data, size, {});
  aperture::LoadOptions withData;
  withData.vertexNormals = true;
  withData.properties = {{aperture::PropertyDomain::Face, "object_id"},
                         {aperture::PropertyDomain::Vertex, "label"}};
  loadBothWays(data, size, withData);
  return 0;
}
