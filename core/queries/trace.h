#pragma once
// Tracing arbitrary rays through a Scene (outside the camera frame loop): for tests and tools
// that aim rays at chosen points, such as the watertightness checks.
#include <cstdint>
#include <glm/glm.hpp>
#include <limits>
#include <vector>

#include "core/engine/scene.h"

namespace aperture {

/// One ray in render space (world minus Scene::renderOrigin()). `dir` need not be unit
/// length; t is then measured in units of |dir|.
struct TraceRay {
  glm::vec3 org{0.0f};
  glm::vec3 dir{0.0f, 0.0f, -1.0f};
  float tnear = 0.0f;
  float tfar = std::numeric_limits<float>::infinity();
};

/// What a ray hit. A miss has geomId == kNoHit and t == +inf.
struct TraceHit {
  static constexpr uint32_t kNoHit = 0xFFFFFFFFu;
  float t = std::numeric_limits<float>::infinity();
  float u = 0, v = 0;        ///< Embree's barycentric coordinates of the hit
  glm::vec3 ng{0.0f};        ///< unnormalised geometric normal as Embree reports it
  uint32_t geomId = kNoHit;  ///< the object (top-level geomID, or the instance's)
  uint32_t primId = kNoHit;  ///< the triangle in the object's mesh, loaded order
  bool hit() const { return geomId != kNoHit; }
};

/// Traces `rays` (closest hit) in packets of `packetWidth` (1, 4, 8 or 16) on the calling
/// thread. Rays Embree cannot take (traceableRay, core/engine/packet.h: a non-finite origin or
/// direction, one past Embree's range, a segment outside [0, ∞]) are not traced: a miss.
/// Returns one hit per ray, in order. Throws Error for a bad packet width.
std::vector<TraceHit> traceRays(const Scene& scene, const std::vector<TraceRay>& rays,
                                int packetWidth = 16);

}  // namespace aperture
