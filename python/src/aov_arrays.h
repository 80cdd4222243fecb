#pragma once
// Framebuffers and frame storage (core/aov/frame_pixels.h) as NumPy arrays, generic over the AOVs
// they hold (aovNames and aovView, core/aov/framebuffer.h): a new AOV of the core appears in Python
// with no code here.
#include <nanobind/nanobind.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/aov/frame_pixels.h"
#include "core/aov/framebuffer.h"

namespace aperture::python {

/// The shape of channel `c`'s array in storage `px` (see frameArrays for `frames`), and its
/// strides in elements.
struct ArrayLayout {
  std::vector<size_t> shape;
  std::vector<int64_t> strides;
  void add(size_t extent, size_t stride) {
    shape.push_back(extent);
    strides.push_back(int64_t(stride));
  }
};
ArrayLayout layoutOf(const FramePixels& px, const PixelChannel& c, size_t frames);

/// The array of channel `c` of `px`, pointing into its storage, which `owner` keeps alive (the
/// array holds a reference to it).
nanobind::object channelArray(const FramePixels& px, const PixelChannel& c, size_t frames,
                              nanobind::handle owner);

/// name -> array of every channel of `px` (channelArray).
nanobind::dict pixelArrays(const FramePixels& px, size_t frames, nanobind::handle owner);

/// name -> array of the frames `fb` holds, float32 or uint32, with no copy: every array points
/// into `fb`, which a capsule keeps alive until the last of them is gone.
/// `frames` = 0: one frame, (H, W) or (H, W, C) (layered hits, "layers.*": (K, H, W), also for K =
/// 1). `frames` = N >= 1: N frames of H rows stacked in `fb` (renderImagesStacked), (N, H, W[, C])
/// (layered hits: (N, K, H, W), a strided view of the layer-major storage).
nanobind::dict frameArrays(std::shared_ptr<Framebuffer> fb, size_t frames);

}  // namespace aperture::python
