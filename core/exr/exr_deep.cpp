#include "core/exr/exr_deep.h"

#include <Imath/ImathBox.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepScanLineInputFile.h>
#include <OpenEXR/ImfDeepScanLineOutputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfPartType.h>

#include <algorithm>
#include <climits>
#include <cstddef>
#include <exception>
#include <filesystem>
#include <vector>

#include "core/engine/layers.h"
#include "core/exr/exr_header.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"

namespace aperture {

namespace {

const char* const kLayerCountAttribute = "aperture.layers";

// Both directions hand OpenEXR the framebuffer's own layer-major arrays, without copying: a
// deep slice holds one pointer per pixel to the pixel's first sample, and sample i lies
// `sampleStride` bytes further on. With layer k of pixel p at [k * n + p], pixel p's pointer is
// &array[p] and the stride is n values, so sample i is layer i.

/// The per-pixel sample pointers into a layer-major array of `n` pixels a layer.
template <typename T>
std::vector<char*> samplePointers(const T* layerMajor, size_t n) {
  std::vector<char*> pointers(n);
  char* base = reinterpret_cast<char*>(const_cast<T*>(layerMajor));
  for (size_t p = 0; p < n; ++p) pointers[p] = base + p * sizeof(T);
  return pointers;
}

/// OpenEXR's slice base for pixel data indexed from the data window's corner `min` (OpenEXR
/// addresses pixel (x, y) at base + x * xStride + y * yStride).
char* sliceBase(void* first, const Imath::V2i& min, size_t xStride, size_t width) {
  const std::ptrdiff_t offset = std::ptrdiff_t(min.x) * std::ptrdiff_t(xStride) +
                                std::ptrdiff_t(min.y) * std::ptrdiff_t(xStride * width);
  return static_cast<char*>(first) - offset;
}

/// The deep channels of the layers, each over the per-pixel pointers of its array.
struct DeepChannels {
  std::vector<char*> depth, distance, primId, geomId;

  DeepChannels(Framebuffer& fb, const std::string& path) {
    const size_t n = fb.pixelCount();
    // DeepSlice::sampleStride is an int.
    if (n > size_t(INT_MAX) / sizeof(float))
      throw Error(cat("deep EXR '", path, "': ", fb.width, "x", fb.height,
                      " pixels are too many for a layer-major deep slice (at most ",
                      size_t(INT_MAX) / sizeof(float), ")"));
    depth = samplePointers(fb.layerDepth.data(), n);
    distance = samplePointers(fb.layerDistance.data(), n);
    primId = samplePointers(fb.layerPrimId.data(), n);
    geomId = samplePointers(fb.layerGeomId.data(), n);
  }

  /// Adds the slices Z, ZBack (the depth again, when `withZBack`), T, primID and geomID.
  void addTo(Imf::DeepFrameBuffer& frame, const Imath::V2i& min, int width, bool withZBack) {
    const size_t n = depth.size();
    const int sampleStride = int(n * sizeof(float));
    auto add = [&](const char* name, Imf::PixelType type, std::vector<char*>& pointers) {
      const size_t xStride = sizeof(char*);
      frame.insert(name,
                   Imf::DeepSlice(type, sliceBase(pointers.data(), min, xStride, size_t(width)),
                                  xStride, xStride * size_t(width), sampleStride));
    };
    add("Z", Imf::FLOAT, depth);
    if (withZBack) add("ZBack", Imf::FLOAT, depth);
    add("T", Imf::FLOAT, distance);
    add("primID", Imf::UINT, primId);
    add("geomID", Imf::UINT, geomId);
  }
};

void insertSampleCounts(Imf::DeepFrameBuffer& frame, std::vector<unsigned>& counts,
                        const Imath::V2i& min, int width) {
  const size_t xStride = sizeof(unsigned);
  frame.insertSampleCountSlice(Imf::Slice(Imf::UINT,
                                          sliceBase(counts.data(), min, xStride, size_t(width)),
                                          xStride, xStride * size_t(width)));
}

/// Per pixel, the number of layers that hold a surface: layers fill from the nearest, so they
/// are the layers before the first miss (primID 0xFFFFFFFF).
std::vector<unsigned> surfaceCounts(const Framebuffer& fb) {
  const size_t n = fb.pixelCount();
  std::vector<unsigned> counts(n, 0);
  for (size_t p = 0; p < n; ++p)
    while (counts[p] < unsigned(fb.layers) && fb.layerPrimId[counts[p] * n + p] != kInvalidId)
      ++counts[p];
  return counts;
}

}  // namespace

std::string deepLayersPath(const std::string& exrPath) {
  return std::filesystem::path(exrPath).replace_extension(".deep.exr").string();
}

void writeDeepLayersExr(const std::string& path, const Framebuffer& fb, const ExrMetadata& meta) {
  if (fb.width <= 0 || fb.height <= 0 || fb.layers <= 0)
    throw Error(cat("cannot write deep EXR '", path, "': no layered hits (", fb.width, "x",
                    fb.height, " pixels, ", fb.layers, " layers)"));
  const size_t ln = size_t(fb.layers) * fb.pixelCount();
  if (fb.layerDepth.size() != ln || fb.layerDistance.size() != ln || fb.layerPrimId.size() != ln ||
      fb.layerGeomId.size() != ln)
    throw Error(cat("cannot write deep EXR '", path, "': the layer arrays do not hold ", fb.layers,
                    " x ", fb.pixelCount(), " values"));

  Imf::Header header = exrHeaderFor(path, fb.width, fb.height, meta);
  header.setType(Imf::DEEPSCANLINE);
  header.compression() = Imf::ZIPS_COMPRESSION;
  header.insert(kLayerCountAttribute, Imf::IntAttribute(fb.layers));
  for (const char* name : {"Z", "ZBack", "T"})
    header.channels().insert(name, Imf::Channel(Imf::FLOAT));
  for (const char* name : {"primID", "geomID"})
    header.channels().insert(name, Imf::Channel(Imf::UINT));

  // OpenEXR reads through the pointers only; the framebuffer stays unchanged.
  Framebuffer& source = const_cast<Framebuffer&>(fb);
  std::vector<unsigned> counts = surfaceCounts(fb);
  DeepChannels channels(source, path);
  Imf::DeepFrameBuffer frame;
  const Imath::V2i origin(0, 0);
  insertSampleCounts(frame, counts, origin, fb.width);
  channels.addTo(frame, origin, fb.width, true);

  writeAtomically(path, [&](const std::string& tmp) {
    Imf::DeepScanLineOutputFile file(tmp.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(fb.height);
  });
}

Framebuffer readDeepLayersExr(const std::string& path) {
  try {
    Imf::DeepScanLineInputFile file(path.c_str());
    const Imf::Header& header = file.header();
    if (!file.isComplete()) throw Error("incomplete file (missing scanlines)");
    for (const char* name : {"Z", "T", "primID", "geomID"})
      if (!header.channels().findChannel(name)) throw Error(cat("no channel ", name));
    const Imath::Box2i window = header.dataWindow();
    const int width = window.max.x - window.min.x + 1;
    const int height = window.max.y - window.min.y + 1;

    std::vector<unsigned> counts(size_t(width) * size_t(height));
    Imf::DeepFrameBuffer countsOnly;
    insertSampleCounts(countsOnly, counts, window.min, width);
    file.setFrameBuffer(countsOnly);
    file.readPixelSampleCounts(window.min.y, window.max.y);
    const unsigned most = counts.empty() ? 0 : *std::max_element(counts.begin(), counts.end());

    AovSet set;
    const auto* recorded = header.findTypedAttribute<Imf::IntAttribute>(kLayerCountAttribute);
    set.layers = recorded ? recorded->value() : int(most);
    if (set.layers < 1 || set.layers > kMaxLayers)
      throw Error(cat(kLayerCountAttribute, " ", set.layers, " is outside [1, ", kMaxLayers, "]"));
    if (most > unsigned(set.layers))
      throw Error(cat("a pixel holds ", most, " samples, more than the ", set.layers, " layers"));

    Framebuffer fb(width, height, set);
    DeepChannels channels(fb, path);
    Imf::DeepFrameBuffer frame;
    insertSampleCounts(frame, counts, window.min, width);
    channels.addTo(frame, window.min, width, false);  // ZBack repeats Z
    // A new frame buffer forgets the counts read, so they are read again into the same array.
    file.setFrameBuffer(frame);
    file.readPixelSampleCounts(window.min.y, window.max.y);
    file.readPixels(window.min.y, window.max.y);
    return fb;
  } catch (const std::exception& e) {
    throw Error(cat("cannot read deep EXR '", path, "': ", e.what()));
  }
}

}  // namespace aperture
