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

/// name -> array of every channel of `px`, pointing into its storage, which `owner` keeps alive
/// (the arrays hold a reference to it).
nanobind::dict pixelArrays(const FramePixels& px, size_t frames, nanobind::handle owner);

/// name -> array of the frames `fb` holds, float32 or uint32, with no copy: every array points
/// into `fb`, which a capsule keeps alive until the last of them is gone.
/// `frames` = 0: one frame, (H, W) or (H, W, C) (layered hits, "layers.*": (K, H, W), also for K =
/// 1). `frames` = N >= 1: N frames of H rows stacked in `fb` (renderImagesStacked), (N, H, W[, C])
/// (layered hits: (N, K, H, W), a strided view of the layer-major storage).
nanobind::dict frameArrays(std::shared_ptr<Framebuffer> fb, size_t frames);

/// Storage for frame arrays that nothing has written: one LargeBuffer block per channel
/// (core/util/huge_pages.h: from 2 MB up on a 2 MB boundary, advised onto huge pages), so that
/// the render threads are the first to touch its pages. Freed with the last array.
class UnwrittenStorage {
 public:
  UnwrittenStorage() = default;
  UnwrittenStorage(const UnwrittenStorage&) = delete;
  UnwrittenStorage& operator=(const UnwrittenStorage&) = delete;
  ~UnwrittenStorage();
  /// `bytes` bytes, unwritten.
  void* allocate(size_t bytes);

 private:
  std::vector<std::pair<void*, size_t>> blocks_;
};

/// A capsule owning `storage`: the owner handed to pixelArrays.
nanobind::capsule ownerOf(std::unique_ptr<UnwrittenStorage> storage);

}  // namespace aperture::python
