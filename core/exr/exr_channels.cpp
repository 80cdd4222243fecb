#include "core/exr/exr_channels.h"

#include <Imath/ImathBox.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <exception>
#include <set>

#include "core/io/atomic_file.h"
#include "core/util/error.h"

namespace aperture {

void writeExrChannels(const std::string& path, int width, int height,
                      const std::vector<ExrChannel>& channels,
                      const std::vector<std::pair<std::string, std::string>>& strings) {
  if (width <= 0 || height <= 0)
    throw Error(cat("cannot write '", path, "': empty image ", width, "x", height));
  if (channels.empty()) throw Error(cat("cannot write '", path, "': no channel"));
  const size_t pixels = size_t(width) * size_t(height);
  Imf::Header header(width, height);
  header.compression() = Imf::ZIP_COMPRESSION;
  for (const auto& [key, value] : strings) header.insert(key, Imf::StringAttribute(value));
  Imf::FrameBuffer frame;
  std::set<std::string> names;
  for (const ExrChannel& c : channels) {
    if (c.name.empty() || !names.insert(c.name).second)
      throw Error(
          cat("cannot write '", path, "': channel name '", c.name, "' is empty or given twice"));
    const size_t n = c.isUint() ? c.uints.size() : c.floats.size();
    if (n != pixels)
      throw Error(cat("cannot write '", path, "': channel '", c.name, "' holds ", n, " values for ",
                      width, "x", height, " pixels"));
    const Imf::PixelType type = c.isUint() ? Imf::UINT : Imf::FLOAT;
    header.channels().insert(c.name, Imf::Channel(type));
    char* base = c.isUint() ? reinterpret_cast<char*>(const_cast<uint32_t*>(c.uints.data()))
                            : reinterpret_cast<char*>(const_cast<float*>(c.floats.data()));
    frame.insert(c.name, Imf::Slice(type, base, 4, 4 * size_t(width)));
  }
  writeAtomically(path, [&](const std::string& tmp) {
    Imf::OutputFile file(tmp.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(height);
  });
}

std::vector<ExrChannel> readExrChannels(const std::string& path, int* width, int* height) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    const int w = window.max.x - window.min.x + 1;
    const int h = window.max.y - window.min.y + 1;
    if (!file.isComplete()) throw Error("incomplete file (missing scanlines)");
    const size_t pixels = size_t(w) * size_t(h);
    std::vector<ExrChannel> out;
    const Imf::ChannelList& list = file.header().channels();
    for (auto it = list.begin(); it != list.end(); ++it) {
      ExrChannel c;
      c.name = it.name();
      if (it.channel().type == Imf::UINT)
        c.uints.assign(pixels, 0);
      else
        c.floats.assign(pixels, 0.0f);
      out.push_back(std::move(c));
    }
    Imf::FrameBuffer frame;
    for (ExrChannel& c : out) {
      const Imf::PixelType type = c.isUint() ? Imf::UINT : Imf::FLOAT;
      char* data = c.isUint() ? reinterpret_cast<char*>(c.uints.data())
                              : reinterpret_cast<char*>(c.floats.data());
      frame.insert(c.name, Imf::Slice::Make(type, data, window, 4, 4 * size_t(w)));
    }
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    if (width) *width = w;
    if (height) *height = h;
    return out;
  } catch (const std::exception& e) {
    throw Error(cat("cannot read EXR '", path, "': ", e.what()));
  }
}

}  // namespace aperture
