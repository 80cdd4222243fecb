// libFuzzer target: the camera-file readers. The first byte picks the format (modulo 5):
// 0 COLMAP text, 1 COLMAP binary, 2 transforms.json, 3 OpenCV JSON, 4 OpenCV YAML. The rest
// is the file; for COLMAP it is split at the first "\n--images--\n" into cameras.* and
// images.* (no separator: all cameras, an empty images file). Files go to a folder made once
// per process under $TMPDIR and removed when the process exits.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "cameras/files/camera_file.h"
#include "core/util/error.h"

namespace {

namespace fs = std::filesystem;

fs::path scratchPath() {
  return fs::temp_directory_path() / ("aperture-fuzz-cameras-" + std::to_string(getpid()));
}

void removeScratch() {
  std::error_code ignored;
  fs::remove_all(scratchPath(), ignored);
}

const fs::path& scratch() {
  static const fs::path dir = [] {
    fs::path d = scratchPath();
    fs::create_directories(d);
    std::atexit(removeScratch);
    return d;
  }();
  return dir;
}

void put(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string body(reinterpret_cast<const char*>(data) + 1, size - 1);
  const fs::path dir = scratch();
  for (const char* name : {"cameras.txt", "images.txt", "cameras.bin", "images.bin"})
    fs::remove(dir / name);
  std::string path;
  switch (data[0] % 5) {
    case 0:
    case 1: {
      const bool binary = data[0] % 5 == 1;
      const std::string separator = "\n--images--\n";
      const size_t at = body.find(separator);
      const std::string ext = binary ? ".bin" : ".txt";
      put(dir / ("cameras" + ext), body.substr(0, at));
      put(dir / ("images" + ext),
          at == std::string::npos ? "" : body.substr(at + separator.size()));
      path = dir.string();
      break;
    }
    case 2:
    case 3:
      path = (dir / (data[0] % 5 == 2 ? "transforms.json" : "calib.json")).string();
      put(path, body);
      break;
    default:
      path = (dir / "calib.yaml").string();
      put(path, body);
      break;
  }
  try {
    aperture::readCameraFile(path);
  } catch (const aperture::Error&) {
    // A clear error is the right answer to a malformed camera file.
  }
  return 0;
}
