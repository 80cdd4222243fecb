#pragma once
// Framebuffers as NumPy arrays, generic over the AOVs a framebuffer holds (aovNames and
// aovView, core/aov/framebuffer.h): a new AOV of the core appears in Python with no code here.
#include <nanobind/nanobind.h>

#include <cstddef>
#include <memory>

#include "core/aov/framebuffer.h"

namespace aperture::python {

/// name -> array of the frames `fb` holds, float32 or uint32, with no copy: every array points
/// into `fb`, which a capsule keeps alive until the last of them is gone.
/// `frames` = 0: one frame, (H, W) or (H, W, C) (layered hits, "layers.*": (K, H, W), also for K =
/// 1). `frames` = N >= 1: N frames of H rows stacked in `fb` (renderImagesStacked), (N, H, W[, C])
/// (layered hits: (N, K, H, W), a strided view of the layer-major storage).
nanobind::dict frameArrays(std::shared_ptr<Framebuffer> fb, size_t frames);

}  // namespace aperture::python
