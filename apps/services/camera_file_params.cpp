#include "apps/services/camera_file_params.h"

#include <filesystem>

#include "cameras/models/calibrated.h"
#include "cameras/registry/resolve.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture::app {

std::vector<const CalibratedImage*> selectImages(const CameraFile& file,
                                                 const std::vector<std::string>& names,
                                                 const std::string& flag) {
  std::vector<const CalibratedImage*> selected;
  if (names.empty()) {
    for (const CalibratedImage& image : file.images) selected.push_back(&image);
    return selected;
  }
  std::vector<std::string> known;
  for (const CalibratedImage& image : file.images) known.push_back(image.name);
  for (const std::string& name : names) {
    const CalibratedImage* found = nullptr;
    for (const CalibratedImage& image : file.images)
      if (image.name == name) found = &image;
    if (!found)
      throw Error(cat(flag, ": ", file.path, " has no image '", name, "' (it has ",
                      file.images.size(), " images)", didYouMean(name, known)));
    selected.push_back(found);
  }
  return selected;
}

ParamSet imageParamSet(const CameraFile& file, const CalibratedImage& image) {
  return paramSetOf(
      calibratedCameraParams(file.sensors.at(size_t(image.sensor)), image.worldToCamera),
      cat(file.path, " image '", image.name, "'"));
}

std::string renderNameOf(const std::string& imageName, const std::string& extension) {
  return std::filesystem::path(imageName).replace_extension(extension).generic_string();
}

}  // namespace aperture::app
