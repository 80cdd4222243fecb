#pragma once
// Where the frame loop stores pixels: the vectors of a Framebuffer, or storage held elsewhere
// (the Python module's NumPy arrays), laid out as a Framebuffer's vectors are.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/aov/framebuffer.h"

namespace aperture {

/// One AOV's storage, laid out as its vector in a Framebuffer: `channels` interleaved 4-byte
/// values a pixel, row-major; layered hits ("layers.*") `layers` images one after the other.
struct PixelChannel {
  std::string name;       ///< as aovNames spells it ("depth", "face.object_id", "layers.primid")
  int channels = 1;       ///< values a pixel
  bool isFloat = true;    ///< float32, else uint32
  int layers = 1;         ///< images of this AOV (K for "layers.*", else 1)
  uint32_t missBits = 0;  ///< the bits of the value a pixel holds where nothing is hit
  void* data = nullptr;   ///< its first value (not owned)
  /// Values of an image of `pixels` pixels.
  size_t valueCount(size_t pixels) const { return pixels * size_t(channels) * size_t(layers); }
};

/// The storage of one image the frame loop renders into: one frame, or frames of one size
/// stacked as rows (renderImagesStacked, core/engine/render.h). Does not own the storage.
struct FramePixels {
  int width = 0, height = 0;
  AovSet aovs;
  /// Per AOV of `aovs`, in aovNames order.
  std::vector<PixelChannel> channels;
  /// Whether the storage already holds every value's miss (a Framebuffer does). When false, the
  /// frame loop writes the misses of each tile before its hits, so every value is written by
  /// the render threads: the storage may start unwritten, and its pages are first touched by
  /// the threads that fill them, never zeroed on one thread first.
  bool missesWritten = false;

  size_t pixelCount() const { return size_t(width) * size_t(height); }
  /// The channel named `name`, or nullptr.
  const PixelChannel* find(const std::string& name) const;
};

/// The channels a framebuffer of `width` x `height` holding `set` has (names, layout and miss
/// values as Framebuffer and aovView give them), with no storage: the caller sets each
/// channel's data, and missesWritten stays false.
FramePixels unboundPixels(int width, int height, const AovSet& set);
/// The storage of `fb` (missesWritten: its constructor filled the misses).
FramePixels framePixelsOf(Framebuffer& fb);

}  // namespace aperture
