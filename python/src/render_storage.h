#pragma once
// The storage Scene.render writes into: the caller's arrays (`out=`), checked against the shape
// and dtype each AOV needs, and fresh storage nothing has written for the others, so the render
// threads are the first to touch every page (no zero-fill on one thread before the render).
#include <nanobind/nanobind.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "core/aov/frame_pixels.h"

namespace aperture::python {

/// The storage of one image of a render (one frame, or frames of one size stacked) and the
/// Python objects behind it.
struct RenderStorage {
  FramePixels pixels;      ///< every channel's data set; missesWritten false
  nanobind::object owner;  ///< the capsule of the fresh storage (None when every AOV was given)
  std::vector<std::pair<std::string, nanobind::object>> given;  ///< the caller's arrays by AOV
};

/// Storage for an image of `width` x `height` (all `frames` stacked; `frames` as frameArrays:
/// 0 for one camera's (H, W[, C]) arrays, N for (N, H, W[, C])) holding `aovs`. `out`: None or a
/// dict AOV name -> NumPy array to write that AOV into; each must be C-contiguous, writeable,
/// of the AOV's shape and dtype (float32 or uint32), and not overlap another. Layered hits
/// ("layers.*") are not written into given arrays. Throws nb::value_error naming the AOV
/// (`what`: the caller's name, "Scene.render") otherwise.
RenderStorage renderStorage(int width, int height, const AovSet& aovs, size_t frames,
                            nanobind::handle out, const char* what);

/// name -> array of the render: the caller's array itself where it gave one (the same object),
/// a view of the fresh storage otherwise.
nanobind::dict renderedArrays(const RenderStorage& storage, size_t frames);

}  // namespace aperture::python
