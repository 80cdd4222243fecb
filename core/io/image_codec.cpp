#include "core/io/image_codec.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "core/util/error.h"
#include "core/util/sanitizers.h"

#ifdef APERTURE_ASAN
#include <sanitizer/lsan_interface.h>
#endif

// A program that links the codec in (aperture_oiio_linked, core/CMakeLists.txt: the test and
// fuzz programs of sanitizer and fuzz builds) defines the entry point itself, and uses it; any
// other loads the plugin. Weak, so that it is null where nothing defines it.
extern "C" const aperture::ImageCodec* APERTURE_IMAGE_CODEC_ENTRY() __attribute__((weak));

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

/// Under AddressSanitizer, the leak check of the end of the process, done now, before the
/// plugin brings OpenImageIO's libraries: LeakSanitizer's exit-time check crashed ("Tracer
/// caught signal 11") in about 1 of 20 ASan runs of a process that had loaded them by dlopen
/// (it reads their threads' dynamic TLS). Like that check, it ends the process on a leak; what
/// is allocated after it is not checked. Elsewhere nothing.
void checkLeaksBeforeLoadingThePlugin() {
#ifdef APERTURE_ASAN
  __lsan_do_leak_check();
#endif
}

const ImageCodec* loadImageCodec() {
  checkLeaksBeforeLoadingThePlugin();
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
  if (!codec) codec = APERTURE_IMAGE_CODEC_ENTRY ? APERTURE_IMAGE_CODEC_ENTRY() : loadImageCodec();
  return *codec;
}

}  // namespace aperture

std::vector<unsigned char> aperture::encodeImage(const std::string& path,
                                                 const ImageToEncode& image) {
  std::vector<unsigned char> bytes;
  std::string error;
  if (!imageCodec().encode(path, image, bytes, error)) throw Error(error);
  return bytes;
}
