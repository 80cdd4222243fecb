#include "core/image_codec.h"

#include "core/error.h"

#ifdef APERTURE_IMAGE_CODEC_LINKED
// Sanitizer and fuzz builds: the codec is linked in (core/CMakeLists.txt says why).
const aperture::ImageCodec& aperture::imageCodec() { return *APERTURE_IMAGE_CODEC_ENTRY(); }

#else

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>

namespace aperture {
namespace {

namespace fs = std::filesystem;

constexpr const char* kPluginFile = "libaperture_oiio.so";

/// Where the plugin may be: $APERTURE_IMAGE_CODEC alone when set; else beside the object that
/// holds this code (the Python module, or the program), beside the running program, and where
/// the build put it.
std::vector<std::string> pluginCandidates() {
  if (const char* chosen = std::getenv("APERTURE_IMAGE_CODEC"); chosen && *chosen) return {chosen};
  std::vector<std::string> paths;
  const auto add = [&paths](const fs::path& path) {
    if (std::find(paths.begin(), paths.end(), path.string()) == paths.end())
      paths.push_back(path.string());
  };
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&pluginCandidates), &info) && info.dli_fname &&
      fs::path(info.dli_fname).is_absolute())
    add(fs::path(info.dli_fname).parent_path() / kPluginFile);
  std::error_code ec;
  const fs::path program = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) add(program.parent_path() / kPluginFile);
#ifdef APERTURE_IMAGE_CODEC_BUILD_PATH
  add(APERTURE_IMAGE_CODEC_BUILD_PATH);
#endif
  return paths;
}

const ImageCodec* loadImageCodec() {
  std::string tried;
  for (const std::string& path : pluginCandidates()) {
    if (!fs::exists(path)) {
      tried += cat("\n  ", path, ": no such file");
      continue;
    }
    void* handle = dlopen(path.c_str(), RTLD_LAZY | RTLD_LOCAL);
    if (!handle) {
      tried += cat("\n  ", path, ": ", dlerror());
      continue;
    }
    using Entry = decltype(&APERTURE_IMAGE_CODEC_ENTRY);
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, kImageCodecEntry));
    if (!entry) {
      tried += cat("\n  ", path, ": no ", kImageCodecEntry, " (a plugin of another version)");
      dlclose(handle);
      continue;
    }
    return entry();  // the plugin stays loaded for the life of the process
  }
  throw Error(cat("cannot load ", kPluginFile,
                  ", aperture's OpenImageIO plugin for PNG, JPEG and TIFF files; tried:", tried));
}

}  // namespace

const ImageCodec& imageCodec() {
  static std::mutex mutex;
  static const ImageCodec* codec = nullptr;
  const std::lock_guard<std::mutex> lock(mutex);
  if (!codec) codec = loadImageCodec();
  return *codec;
}

}  // namespace aperture

#endif  // APERTURE_IMAGE_CODEC_LINKED

std::vector<unsigned char> aperture::encodeImage(const std::string& path,
                                                 const ImageToEncode& image) {
  std::vector<unsigned char> bytes;
  std::string error;
  if (!imageCodec().encode(path, image, bytes, error)) throw Error(error);
  return bytes;
}
