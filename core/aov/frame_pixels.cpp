#include "core/aov/frame_pixels.h"

#include <cstring>

namespace aperture {

namespace {

/// The channels of `fb` by aovView, each with the bits of its first value: a framebuffer of
/// one pixel holds just the miss values its constructor wrote.
std::vector<PixelChannel> channelsOf(const Framebuffer& fb) {
  std::vector<PixelChannel> out;
  for (const std::string& name : aovNames(fb)) {
    const ImageView v = aovView(fb, name);
    PixelChannel c;
    c.name = name;
    c.channels = v.channels;
    c.isFloat = v.f32 != nullptr;
    c.layers = v.layers;
    const void* first = c.isFloat ? static_cast<const void*>(v.f32) : v.u32;
    c.data = const_cast<void*>(first);
    if (first) std::memcpy(&c.missBits, first, sizeof(uint32_t));
    out.push_back(c);
  }
  return out;
}

}  // namespace

const PixelChannel* FramePixels::find(const std::string& name) const {
  for (const PixelChannel& c : channels)
    if (c.name == name) return &c;
  return nullptr;
}

FramePixels unboundPixels(int width, int height, const AovSet& set) {
  FramePixels px;
  px.width = width;
  px.height = height;
  px.aovs = set;
  px.channels = channelsOf(Framebuffer(1, 1, set));
  for (PixelChannel& c : px.channels) c.data = nullptr;
  return px;
}

FramePixels framePixelsOf(Framebuffer& fb) {
  FramePixels px;
  px.width = fb.width;
  px.height = fb.height;
  px.aovs = fb.aovSet();
  px.channels = channelsOf(fb);
  px.missesWritten = true;
  return px;
}

}  // namespace aperture
