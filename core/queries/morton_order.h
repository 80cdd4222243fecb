#pragma once
// Points in Morton (Z-order) order: queries over many points visit them so that consecutive
// points are neighbours in space and share cached nodes: winding numbers and closest points
// (mortonOrder), parity (its own bucketed order over core/util/morton.h's codes, inside.cpp).
#include <cstddef>
#include <glm/glm.hpp>
#include <vector>

namespace aperture {

/// The indices of `count` points (3 doubles each) sorted by the Morton code of their cell in a
/// 2^21-per-axis grid over the box [lo, hi] (points outside it clamped to it, non-finite
/// coordinates to its low side). Parallel; ties keep index order, so the result is the same
/// for any thread count.
std::vector<size_t> mortonOrder(const double* points, size_t count, const glm::dvec3& lo,
                                const glm::dvec3& hi);

}  // namespace aperture
