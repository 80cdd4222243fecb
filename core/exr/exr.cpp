#include "core/exr/exr.h"

#include <Imath/ImathBox.h>
#include <Imath/ImathMatrix.h>
#include <Imath/ImathVec.h>
#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMatrixAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfStringVectorAttribute.h>
#include <OpenEXR/ImfThreading.h>
#include <OpenEXR/ImfVecAttribute.h>

#include <algorithm>
#include <cstddef>
#include <deque>
#include <exception>
#include <limits>

#include "core/aov/aov_table.h"
#include "core/engine/layers.h"
#include "core/exr/exr_header.h"
#include "core/io/atomic_file.h"
#include "core/util/error.h"

namespace aperture {

namespace {

struct CompressionName {
  const char* name;
  ExrCompression value;
  Imf::Compression imf;
};
constexpr CompressionName kCompressions[] = {
    {"none", ExrCompression::None, Imf::NO_COMPRESSION},
    {"rle", ExrCompression::Rle, Imf::RLE_COMPRESSION},
    {"zips", ExrCompression::Zips, Imf::ZIPS_COMPRESSION},
    {"zip", ExrCompression::Zip, Imf::ZIP_COMPRESSION},
    {"piz", ExrCompression::Piz, Imf::PIZ_COMPRESSION},
    {"pxr24", ExrCompression::Pxr24, Imf::PXR24_COMPRESSION},
    {"b44", ExrCompression::B44, Imf::B44_COMPRESSION},
    {"b44a", ExrCompression::B44a, Imf::B44A_COMPRESSION},
    {"dwaa", ExrCompression::Dwaa, Imf::DWAA_COMPRESSION},
    {"dwab", ExrCompression::Dwab, Imf::DWAB_COMPRESSION},
};

Imf::Compression toImf(ExrCompression c) {
  for (const auto& entry : kCompressions)
    if (entry.value == c) return entry.imf;
  throw Error(cat("invalid EXR compression value ", int(c)));
}

// Matrix convention. CameraDescription holds GLM matrices for column vectors (p' = M p), and
// GLM indexes m[column][row]. OpenEXR/Imath matrices act on row vectors (p' = p X) and index
// x[row][column]. Since X = transpose(M) and the index orders are swapped as well, the element
// arrays coincide: X[i][j] = M[i][j] with GLM's indexing.
Imath::M44d toImath(const glm::dmat4& m) {
  Imath::M44d x;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) x[i][j] = m[i][j];
  return x;
}

glm::dmat4 toGlm(const Imath::M44d& x) {
  glm::dmat4 m(1.0);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m[i][j] = x[i][j];
  return m;
}

Imath::V3d toImath(const glm::dvec3& v) { return Imath::V3d(v.x, v.y, v.z); }
glm::dvec3 toGlm(const Imath::V3d& v) { return glm::dvec3(v.x, v.y, v.z); }

/// The only fisheye mapping aperture writes: the angle from the axis is proportional to the
/// distance from the centre (FisheyeProjection).
const char* const kFisheyeMapping = "equidistant";

/// The property AOVs among an EXR's channels: UINT channels named "face.NAME" / "vertex.NAME",
/// in the file's (name-sorted) channel order.
std::vector<PropertyAov> propertyChannelsOf(const Imf::ChannelList& channels) {
  std::vector<PropertyAov> found;
  for (auto it = channels.begin(); it != channels.end(); ++it) {
    const std::string name = it.name();
    if (it.channel().type != Imf::UINT) continue;
    if (name.rfind("face.", 0) != 0 && name.rfind("vertex.", 0) != 0) continue;
    const AovSet set = parseAovSet(name);
    if (set.properties.size() == 1) found.push_back(set.properties.front());
  }
  return found;
}

/// Adds a channel and a slice over interleaved data (`components` values a pixel).
void addChannel(Imf::Header& header, Imf::FrameBuffer& frame, const char* name, Imf::PixelType type,
                const void* data, size_t valueSize, int components, int width) {
  header.channels().insert(name, Imf::Channel(type));
  const size_t xStride = valueSize * size_t(components);
  frame.insert(name, Imf::Slice(type, static_cast<char*>(const_cast<void*>(data)), xStride,
                                xStride * size_t(width)));
}

/// A calibrated camera's lens: aperture.lens.model and .pixelCentre (strings), .paramNames
/// (COLMAP's order, space-separated) and one double per parameter (aperture.lens.fx, ...).
void addLensAttributes(Imf::Header& header, const LensProjection& lens) {
  header.insert("aperture.lens.model", Imf::StringAttribute(lens.model));
  header.insert("aperture.lens.pixelCentre", Imf::StringAttribute(lens.pixelCentre));
  header.insert("aperture.lens.paramNames", Imf::StringAttribute(join(lens.paramNames, " ")));
  for (size_t k = 0; k < lens.params.size(); ++k)
    header.insert("aperture.lens." + lens.paramNames[k], Imf::DoubleAttribute(lens.params[k]));
}

std::optional<LensProjection> readLensAttributes(const Imf::Header& header) {
  using S = Imf::StringAttribute;
  auto* model = header.findTypedAttribute<S>("aperture.lens.model");
  auto* centre = header.findTypedAttribute<S>("aperture.lens.pixelCentre");
  auto* names = header.findTypedAttribute<S>("aperture.lens.paramNames");
  if (!model || !centre || !names) return std::nullopt;
  LensProjection lens{model->value(), {}, {}, centre->value()};
  std::istringstream words(names->value());
  for (std::string name; words >> name;) {
    auto* v = header.findTypedAttribute<Imf::DoubleAttribute>("aperture.lens." + name);
    if (!v) throw Error(cat("aperture.lens.paramNames names '", name, "' but the header lacks it"));
    lens.paramNames.push_back(name);
    lens.params.push_back(v->value());
  }
  return lens;
}

/// The standard worldToCamera and worldToNDC (float) with their double copies, and the
/// projection attributes of the panoramas, which have no worldToNDC (README, "EXR channels").
void addProjectionAttributes(Imf::Header& header, const CameraDescription& cam) {
  const Imath::M44d worldToCamera = toImath(cam.exrCameraFromWorld);
  Imf::addWorldToCamera(header, Imath::M44f(worldToCamera));
  header.insert("aperture.worldToCamera", Imf::M44dAttribute(worldToCamera));
  if (cam.ndcFromWorld) {
    const Imath::M44d worldToNdc = toImath(*cam.ndcFromWorld);
    Imf::addWorldToNDC(header, Imath::M44f(worldToNdc));
    header.insert("aperture.worldToNDC", Imf::M44dAttribute(worldToNdc));
  }
  if (cam.equirect) {
    const glm::dvec2 lon = cam.equirect->longitudeDeg, lat = cam.equirect->latitudeDeg;
    header.insert("aperture.equirect.longitudeRange", Imf::V2dAttribute(Imath::V2d(lon.x, lon.y)));
    header.insert("aperture.equirect.latitudeRange", Imf::V2dAttribute(Imath::V2d(lat.x, lat.y)));
  }
  if (cam.fisheye) {
    const glm::dvec2 centre = cam.fisheye->centerPx;
    header.insert("aperture.fisheye.mapping", Imf::StringAttribute(kFisheyeMapping));
    header.insert("aperture.fisheye.fov", Imf::DoubleAttribute(cam.fisheye->fovDeg));
    header.insert("aperture.fisheye.center", Imf::V2dAttribute(Imath::V2d(centre.x, centre.y)));
    header.insert("aperture.fisheye.radius", Imf::DoubleAttribute(cam.fisheye->radiusPx));
  }
  if (cam.lens) addLensAttributes(header, *cam.lens);
}

void addHeaderAttributes(Imf::Header& header, const ExrMetadata& meta) {
  const CameraDescription& cam = meta.camera;
  addProjectionAttributes(header, cam);
  header.insert("aperture.camera.type", Imf::StringAttribute(cam.type));
  header.insert("aperture.camera.eye", Imf::V3dAttribute(toImath(cam.eye)));
  header.insert("aperture.camera.U", Imf::V3dAttribute(toImath(cam.u)));
  header.insert("aperture.camera.V", Imf::V3dAttribute(toImath(cam.v)));
  header.insert("aperture.camera.W", Imf::V3dAttribute(toImath(cam.w)));
  header.insert("aperture.camera.d", Imf::DoubleAttribute(cam.d));
  header.insert("aperture.camera.viewport", Imf::V2dAttribute(Imath::V2d(cam.vw, cam.vh)));
  header.insert("aperture.spp", Imf::IntAttribute(cam.spp));
  header.insert("aperture.renderSeconds", Imf::DoubleAttribute(meta.renderSeconds));
  for (const auto& [name, value] : cam.extra)
    header.insert("aperture.camera." + name, Imf::StringAttribute(value));
  for (const auto& [name, value] : meta.strings) header.insert(name, Imf::StringAttribute(value));
  for (const auto& [name, values] : meta.stringVectors)
    header.insert(name, Imf::StringVectorAttribute(values));
  header.insert("software", Imf::StringAttribute("aperture " APERTURE_VERSION));
}

/// The header with the display window and the standard screen attributes of `cam`. Throws
/// Error when the pixel aspect ratio is outside the range OpenEXR accepts.
Imf::Header standardHeader(const std::string& path, int width, int height,
                           const CameraDescription& cam) {
  const double ratio = cam.pixelAspectRatio;
  // OpenEXR's Header::sanityCheck rejects ratios outside [1e-6, 1e6].
  if (!(ratio >= 1e-6 && ratio <= 1e6))
    throw Error(cat("cannot write '", path, "': pixel aspect ratio ", ratio, " (viewport ", cam.vw,
                    "x", cam.vh, " over ", width, "x", height,
                    " pixels) is outside OpenEXR's range [1e-6, 1e6]"));
  const glm::dvec2 c = cam.screenWindowCenter;
  return Imf::Header(width, height, float(ratio), Imath::V2f(float(c.x), float(c.y)),
                     float(cam.screenWindowWidth));
}

}  // namespace

Imf::Header exrHeaderFor(const std::string& path, int width, int height, const ExrMetadata& meta) {
  Imf::Header header = standardHeader(path, width, height, meta.camera);
  addHeaderAttributes(header, meta);
  return header;
}

namespace {

template <typename T, typename A>
const T* findValue(const Imf::Header& header, const char* name) {
  const A* attribute = header.findTypedAttribute<A>(name);
  return attribute ? &attribute->value() : nullptr;
}

/// The standard screen attributes, the matrices (the double copies where present) and the
/// panorama projection.
void readProjection(const Imf::Header& header, CameraDescription& cam) {
  cam.pixelAspectRatio = header.pixelAspectRatio();
  cam.screenWindowCenter = glm::dvec2(header.screenWindowCenter().x, header.screenWindowCenter().y);
  cam.screenWindowWidth = header.screenWindowWidth();
  if (auto* m = findValue<Imath::M44d, Imf::M44dAttribute>(header, "aperture.worldToCamera"))
    cam.exrCameraFromWorld = toGlm(*m);
  else if (Imf::hasWorldToCamera(header))
    cam.exrCameraFromWorld = toGlm(Imath::M44d(Imf::worldToCamera(header)));
  if (auto* m = findValue<Imath::M44d, Imf::M44dAttribute>(header, "aperture.worldToNDC"))
    cam.ndcFromWorld = toGlm(*m);
  else if (Imf::hasWorldToNDC(header))
    cam.ndcFromWorld = toGlm(Imath::M44d(Imf::worldToNDC(header)));
  using V2 = Imf::V2dAttribute;
  auto* lon = findValue<Imath::V2d, V2>(header, "aperture.equirect.longitudeRange");
  auto* lat = findValue<Imath::V2d, V2>(header, "aperture.equirect.latitudeRange");
  if (lon && lat)
    cam.equirect = EquirectProjection{glm::dvec2(lon->x, lon->y), glm::dvec2(lat->x, lat->y)};
  auto* mapping = findValue<std::string, Imf::StringAttribute>(header, "aperture.fisheye.mapping");
  auto* fov = findValue<double, Imf::DoubleAttribute>(header, "aperture.fisheye.fov");
  auto* centre = findValue<Imath::V2d, V2>(header, "aperture.fisheye.center");
  auto* radius = findValue<double, Imf::DoubleAttribute>(header, "aperture.fisheye.radius");
  if (mapping && *mapping != kFisheyeMapping)
    throw Error(cat("aperture.fisheye.mapping '", *mapping, "' is not '", kFisheyeMapping, "'"));
  if (mapping && fov && centre && radius)
    cam.fisheye = FisheyeProjection{*fov, glm::dvec2(centre->x, centre->y), *radius};
  cam.lens = readLensAttributes(header);
}

void readHeaderAttributes(const Imf::Header& header, int width, int height, ExrMetadata* meta) {
  *meta = ExrMetadata();
  CameraDescription& cam = meta->camera;
  cam.width = width;
  cam.height = height;
  readProjection(header, cam);
  if (auto* s = findValue<std::string, Imf::StringAttribute>(header, "aperture.camera.type"))
    cam.type = *s;
  const std::pair<const char*, glm::dvec3*> vectors[] = {{"aperture.camera.eye", &cam.eye},
                                                         {"aperture.camera.U", &cam.u},
                                                         {"aperture.camera.V", &cam.v},
                                                         {"aperture.camera.W", &cam.w}};
  for (const auto& [name, target] : vectors)
    if (auto* v = findValue<Imath::V3d, Imf::V3dAttribute>(header, name)) *target = toGlm(*v);
  if (auto* d = findValue<double, Imf::DoubleAttribute>(header, "aperture.camera.d")) cam.d = *d;
  if (auto* v = findValue<Imath::V2d, Imf::V2dAttribute>(header, "aperture.camera.viewport")) {
    cam.vw = v->x;
    cam.vh = v->y;
  }
  if (auto* n = findValue<int, Imf::IntAttribute>(header, "aperture.spp")) cam.spp = *n;
  if (auto* t = findValue<double, Imf::DoubleAttribute>(header, "aperture.renderSeconds"))
    meta->renderSeconds = *t;

  // Every other string attribute: camera extras back into `extra`, the rest into `strings`.
  const std::string extraPrefix = "aperture.camera.";
  for (auto it = header.begin(); it != header.end(); ++it) {
    if (const auto* v = dynamic_cast<const Imf::StringVectorAttribute*>(&it.attribute()))
      meta->stringVectors.emplace_back(it.name(), v->value());
    const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute());
    if (!s) continue;
    const std::string name = it.name();
    if (name == "aperture.camera.type" || name == "software" ||
        name == "aperture.fisheye.mapping" || name.compare(0, 14, "aperture.lens.") == 0)
      continue;
    if (name.compare(0, extraPrefix.size(), extraPrefix) == 0)
      cam.extra.emplace_back(name.substr(extraPrefix.size()), s->value());
    else
      meta->strings.emplace_back(name, s->value());
  }
}

}  // namespace

ExrCompression parseExrCompression(const std::string& name) {
  std::string known;
  for (const auto& entry : kCompressions) {
    if (name == entry.name) return entry.value;
    known += std::string(known.empty() ? "" : " ") + entry.name;
  }
  throw Error(cat("unknown EXR compression '", name, "' (known: ", known, ")"));
}

std::string exrCompressionName(ExrCompression c) {
  for (const auto& entry : kCompressions)
    if (entry.value == c) return entry.name;
  throw Error(cat("invalid EXR compression value ", int(c)));
}

int exrThreads() { return Imf::globalThreadCount(); }

namespace {
/// Sets OpenEXR's pool to `threads` (OpenEXR does nothing when it has that many already:
/// 0.06 us a call); returns the count it had.
int setExrThreads(int threads) {
  const int previous = Imf::globalThreadCount();
  Imf::setGlobalThreadCount(threads);
  return previous;
}
}  // namespace

ExrEncodingThreads::ExrEncodingThreads(int threads, ExrCompression compression)
    : previous_(setExrThreads(threads > 1 && compression != ExrCompression::None ? threads : 0)) {}

ExrEncodingThreads::~ExrEncodingThreads() { setExrThreads(previous_); }

void writeExr(const std::string& path, const Framebuffer& fb, const ExrMetadata& meta,
              const ExrOptions& options) {
  if (fb.width <= 0 || fb.height <= 0)
    throw Error(
        cat("cannot write '", path, "': empty framebuffer (", fb.width, "x", fb.height, ")"));
  const size_t n = fb.pixelCount();
  auto checkSize = [&](const char* aov, size_t have, size_t perPixel) {
    if (have != n * perPixel)
      throw Error(cat("cannot write '", path, "': AOV ", aov, " holds ", have, " values, ",
                      "expected ", n * perPixel));
  };

  Imf::Header header = exrHeaderFor(path, fb.width, fb.height, meta);
  header.compression() = toImf(options.compression);

  Imf::FrameBuffer frame;
  std::deque<std::vector<half>> halves;  // the half copies of the rows written as half
  const int w = fb.width;
  for (const AovRow& row : aovTable()) {
    if (!fb.has(Aov(row.bit))) continue;
    const int channels = row.channels();
    checkSize(row.name.c_str(), valueCount(fb, row), size_t(channels));
    const char* data = nullptr;
    Imf::PixelType type = Imf::FLOAT;
    size_t valueSize = sizeof(float);
    if (!row.isFloat()) {
      data = reinterpret_cast<const char*>(uintPixels(fb, row).data());
      type = Imf::UINT;
      valueSize = sizeof(uint32_t);
    } else if (row.halfInExr && options.halfColor) {
      const std::vector<float>& values = floatPixels(fb, row);
      data =
          reinterpret_cast<const char*>(halves.emplace_back(values.begin(), values.end()).data());
      type = Imf::HALF;
      valueSize = sizeof(half);
    } else {
      data = reinterpret_cast<const char*>(floatPixels(fb, row).data());
    }
    for (int c = 0; c < channels; ++c)
      addChannel(header, frame, row.exrChannels[size_t(c)].c_str(), type,
                 data + size_t(c) * valueSize, valueSize, channels, w);
  }
  std::vector<std::string> propertyNames;  // the properties' channel names
  for (const PropertyChannel& p : fb.properties) propertyNames.push_back(p.property.aovName());
  for (size_t j = 0; j < fb.properties.size(); ++j) {
    checkSize(propertyNames[j].c_str(), fb.properties[j].values.size(), 1);
    addChannel(header, frame, propertyNames[j].c_str(), Imf::UINT, fb.properties[j].values.data(),
               sizeof(uint32_t), 1, w);
  }
  // Layered hits (core/engine/layers.h): layer k (0-based, nearest first) is the OpenEXR layer
  // "hit<k>" with a channel per layered row of the AOV table: hit0.Z hit0.T hit0.primID
  // hit0.geomID hit1.Z ..., each of its row's type, its miss value past the last surface.
  const int flatLayers = options.layersInDeepFile ? 0 : fb.layers;
  for (const AovRow& row : aovTable()) {
    if (!row.layered()) continue;
    const bool f = row.layerF32 != nullptr;
    checkSize("layers", f ? layerFloatPixels(fb, row).size() : layerUintPixels(fb, row).size(),
              size_t(fb.layers));
  }
  for (int k = 0; k < flatLayers; ++k) {
    const size_t at = size_t(k) * n;
    for (const AovRow& row : aovTable()) {
      if (row.layerF32)
        addChannel(header, frame, layerChannelName(k, row).c_str(), Imf::FLOAT,
                   layerFloatPixels(fb, row).data() + at, sizeof(float), 1, w);
      else if (row.layerU32)
        addChannel(header, frame, layerChannelName(k, row).c_str(), Imf::UINT,
                   layerUintPixels(fb, row).data() + at, sizeof(uint32_t), 1, w);
    }
  }
  if (header.channels().begin() == header.channels().end())
    throw Error(cat("cannot write '", path, "': the framebuffer holds no AOV"));

  writeAtomically(path, [&](const std::string& tmp) {
    Imf::OutputFile file(tmp.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(fb.height);
  });
}

Framebuffer readExr(const std::string& path, ExrMetadata* meta) {
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i window = header.dataWindow();
    const int width = window.max.x - window.min.x + 1;
    const int height = window.max.y - window.min.y + 1;
    if (!file.isComplete()) throw Error("incomplete file (missing scanlines)");

    const Imf::ChannelList& channels = header.channels();
    auto present = [&](const char* name) { return channels.findChannel(name) != nullptr; };
    AovMask mask = 0;
    for (const AovRow& row : aovTable())
      for (const std::string& name : row.exrChannels)
        if (present(name.c_str())) mask |= row.bit;
    AovSet set(mask);
    set.properties = propertyChannelsOf(channels);
    // Layer k is there when the first layered row's channel of it is (hit<k>.Z).
    const AovRow& firstLayered = *std::find_if(aovTable().begin(), aovTable().end(),
                                               [](const AovRow& r) { return r.layered(); });
    while (set.layers < kMaxLayers && present(layerChannelName(set.layers, firstLayered).c_str()))
      ++set.layers;
    if (set.empty())
      throw Error(
          cat("no aperture channels (", exrChannelSummary(), ", face.*, vertex.*, hit0.Z ...)"));

    Framebuffer fb(width, height, set);
    Imf::FrameBuffer frame;
    auto insert = [&](const char* name, Imf::PixelType type, void* data, size_t valueSize,
                      int components, double fill) {
      const size_t xStride = valueSize * size_t(components);
      frame.insert(
          name, Imf::Slice::Make(type, data, window, xStride, xStride * size_t(width), 1, 1, fill));
    };
    for (const AovRow& row : aovTable()) {
      if ((mask & row.bit) == 0) continue;
      const int components = row.channels();
      for (int c = 0; c < components; ++c) {
        const char* name = row.exrChannels[size_t(c)].c_str();
        if (row.isFloat())
          insert(name, Imf::FLOAT, floatPixels(fb, row).data() + c, sizeof(float), components,
                 row.fillOfAbsent(c));
        else
          insert(name, Imf::UINT, uintPixels(fb, row).data() + c, sizeof(uint32_t), components,
                 row.fillOfAbsent(c));
      }
    }
    std::vector<std::string> propertyNames;  // the properties' channel names
    for (const PropertyChannel& p : fb.properties) propertyNames.push_back(p.property.aovName());
    for (size_t j = 0; j < fb.properties.size(); ++j)
      insert(propertyNames[j].c_str(), Imf::UINT, fb.properties[j].values.data(), sizeof(uint32_t),
             1, double(kInvalidId));
    for (int k = 0; k < set.layers; ++k) {
      const size_t at = size_t(k) * fb.pixelCount();
      for (const AovRow& row : aovTable()) {
        if (row.layerF32)
          insert(layerChannelName(k, row).c_str(), Imf::FLOAT, (fb.*row.layerF32).data() + at,
                 sizeof(float), 1, row.miss);
        else if (row.layerU32)
          insert(layerChannelName(k, row).c_str(), Imf::UINT, (fb.*row.layerU32).data() + at,
                 sizeof(uint32_t), 1, row.miss);
      }
    }
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    if (meta) readHeaderAttributes(header, width, height, meta);
    return fb;
  } catch (const std::exception& e) {
    throw Error(cat("cannot read EXR '", path, "': ", e.what()));
  }
}

bool isCompleteExr(const std::string& path) {
  try {
    Imf::InputFile file(path.c_str());
    if (!file.isComplete()) return false;
    // The line offset table of a truncated file can still look complete, so decode every
    // scanline into one reused row per channel (y stride 0).
    const Imath::Box2i window = file.header().dataWindow();
    const size_t width = size_t(window.max.x - window.min.x + 1);
    const Imf::ChannelList& channels = file.header().channels();
    size_t channelCount = 0;
    for (auto it = channels.begin(); it != channels.end(); ++it) ++channelCount;
    std::vector<uint32_t> row(width * channelCount);
    Imf::FrameBuffer frame;
    size_t index = 0;
    for (auto it = channels.begin(); it != channels.end(); ++it, ++index) {
      const Imf::PixelType type = it.channel().type == Imf::UINT ? Imf::UINT : Imf::FLOAT;
      char* base = reinterpret_cast<char*>(row.data() + index * width) -
                   std::ptrdiff_t(window.min.x) * std::ptrdiff_t(sizeof(uint32_t));
      frame.insert(it.name(), Imf::Slice(type, base, sizeof(uint32_t), 0, it.channel().xSampling,
                                         it.channel().ySampling));
    }
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

std::vector<std::string> exrChannelNames(const AovSet& set, const ExrOptions& options) {
  const AovMask aovs = set.mask;
  std::vector<std::string> names;
  for (const AovRow& row : aovTable())
    if (aovs & row.bit) names.insert(names.end(), row.exrChannels.begin(), row.exrChannels.end());
  for (const PropertyAov& p : set.properties) names.push_back(p.aovName());
  const int flatLayers = options.layersInDeepFile ? 0 : set.layers;
  for (int k = 0; k < flatLayers; ++k)
    for (const AovRow& row : aovTable())
      if (row.layered()) names.push_back(layerChannelName(k, row));
  return names;
}

ExrHeader readExrHeader(const std::string& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i window = header.dataWindow();
    ExrHeader result;
    result.width = window.max.x - window.min.x + 1;
    result.height = window.max.y - window.min.y + 1;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it)
      result.channels.emplace_back(it.name());
    readHeaderAttributes(header, result.width, result.height, &result.meta);
    return result;
  } catch (const std::exception& e) {
    throw Error(cat("cannot read EXR header of '", path, "': ", e.what()));
  }
}

}  // namespace aperture
