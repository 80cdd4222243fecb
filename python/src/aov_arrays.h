#pragma once
// Framebuffers as NumPy arrays, generic over the AOVs a framebuffer holds (aovNames and
// aovView, core/framebuffer.h): a new AOV of the core appears in Python with no code here.
#include <nanobind/nanobind.h>

#include <memory>
#include <vector>

#include "core/framebuffer.h"

namespace aperture::python {

/// name -> array (H, W) or (H, W, C) of one frame (with frameAxis: (1, H, W[, C])), float32
/// or uint32. No copy: every array points into `fb`, which a capsule keeps alive until the last of
/// them is gone.
nanobind::dict frameArrays(std::shared_ptr<Framebuffer> fb, bool frameAxis);

/// name -> array (N, H, W[, C]) of frames of one size, copied once into one block per AOV
/// (each frame is freed after its copy); the frames of one size cannot share one block
/// without the framebuffer owning external storage.
nanobind::dict stackedArrays(std::vector<Framebuffer>& frames);

}  // namespace aperture::python
