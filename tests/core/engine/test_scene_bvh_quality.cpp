// The BVH build qualities as Embree 3.13 builds them. "high" differs from "medium" by Embree's
// spatial splits, which Embree leaves out of a robust build: with robust traversal (the
// default) high builds the same BVH as medium. The --bvh-quality help and docs/batch.md say
// so; these tests hold them to it, and fail if an Embree release changes it.
#include <gtest/gtest.h>

#include <cmath>

#include "core/engine/scene.h"
#include "core/mesh/mesh.h"
#include "tests/numerics_support.h"

namespace aperture {
namespace {

/// Embree's memory after building the procedural spheres (200,000 triangles, which spatial
/// splits reach) with `quality` and `robust`.
long long embreeBytesOf(BvhQuality quality, bool robust) {
  static const Mesh spheres = [] {
    Mesh m = makeProcedural("procedural:spheres?tris=200000");
    finishMesh(m, LoadOptions{});
    return m;
  }();
  BuildOptions b;
  b.quality = quality;
  b.robust = robust;
  return Scene(test::numericsDevice(), {&spheres}, b).stats().embreeBytes;
}

/// |a − b| relative to b. Embree's thread-local allocation blocks may differ slightly between
/// two builds of the same BVH, so the comparisons below allow 1 %.
double relativeDifference(long long a, long long b) { return std::abs(double(a - b)) / double(b); }

TEST(BvhQuality, HighBuildsWhatMediumDoesWhenRobust) {
  EXPECT_LT(relativeDifference(embreeBytesOf(BvhQuality::High, true),
                               embreeBytesOf(BvhQuality::Medium, true)),
            0.01);
}

TEST(BvhQuality, HighAddsSpatialSplitsWithoutRobust) {
  // The same comparison without robust traversal: the split references make high's BVH
  // larger (5.5 % here), so the test above can tell the two builds apart.
  const long long high = embreeBytesOf(BvhQuality::High, false);
  const long long medium = embreeBytesOf(BvhQuality::Medium, false);
  EXPECT_GT(high, medium);
  EXPECT_GT(relativeDifference(high, medium), 0.03);
}

}  // namespace
}  // namespace aperture
