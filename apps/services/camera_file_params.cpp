#include "apps/services/camera_file_params.h"

#include <cmath>
#include <filesystem>
#include <limits>

#include "cameras/models/calibrated.h"
#include "cameras/registry/resolve.h"
#include "core/util/error.h"
#include "core/util/spelling.h"
#include "core/util/units.h"

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

namespace {

/// The image size of a view of aspect width / height `aspect` (none: unknown) at `size`.
glm::ivec2 gltfImageSize(std::optional<double> aspect, const GltfImageSize& size,
                         const std::string& context) {
  const auto side = [&](double x) { return int(std::max(1.0, std::round(x))); };
  if (size.width && size.height) {
    if (aspect && std::abs(double(*size.width) - double(*size.height) * *aspect) > 1.0)
      throw Error(cat(context, ": the image ", *size.width, "x", *size.height,
                      " does not have the camera's aspect ratio ", *aspect, " (width ",
                      side(double(*size.height) * *aspect), " for height ", *size.height,
                      "); give that size, or one side only"));
    return {*size.width, *size.height};
  }
  if (!aspect)
    throw Error(cat(context,
                    ": the camera gives no aspectRatio, so the image size is needed: give "
                    "both sides (--size W,H)"));
  if (size.width) return {*size.width, side(double(*size.width) / *aspect)};
  const int height = size.height ? *size.height : size.defaultHeight;
  return {side(double(height) * *aspect), height};
}

}  // namespace

CameraParams gltfCameraParams(const SceneCamera& camera, const glm::dmat4& cvCameraFromWorld,
                              const GltfImageSize& size, const std::string& context) {
  CameraParams p;
  const CameraFrame frame = frameOfCvCameraFromWorld(cvCameraFromWorld);
  p.eye = frame.e;
  p.dir = -frame.w;
  p.up = frame.v;
  std::optional<double> aspect;
  if (camera.projection == SceneCamera::Projection::Perspective) {
    p.type = "perspective";
    p.fovDeg = camera.yfov * kDegPerRad;
    p.fovAxis = FovAxis::Y;
    p.clip = glm::dvec2(camera.znear,
                        camera.zfar ? *camera.zfar : double(std::numeric_limits<float>::max()));
    aspect = camera.aspectRatio;
  } else {
    p.type = "orthographic";
    if (!(camera.xmag > 0 && camera.ymag > 0))
      throw Error(cat(context, ": xmag ", camera.xmag, " and ymag ", camera.ymag,
                      " must be > 0 (the half-extents of the view)"));
    p.viewport = glm::dvec2(2.0 * camera.xmag, 2.0 * camera.ymag);
    aspect = camera.xmag / camera.ymag;
  }
  if (aspect && !(*aspect > 0 && std::isfinite(*aspect)))
    throw Error(cat(context, ": aspect ratio ", *aspect, " must be finite and > 0"));
  const glm::ivec2 wh = gltfImageSize(aspect, size, context);
  p.width = wh.x;
  p.height = wh.y;
  return p;
}

ParamSet imageParamSet(const CameraFile& file, const CalibratedImage& image,
                       const GltfImageSize& gltfSize) {
  const std::string source = cat(file.path, " image '", image.name, "'");
  CameraParams p;
  if (image.gltfCamera >= 0) {
    const SceneCamera& camera = file.gltfCameras.at(size_t(image.gltfCamera));
    p = gltfCameraParams(camera, image.cvCameraFromWorld, gltfSize,
                         cat(file.path, " camera '", image.name, "' (/nodes/", camera.node, ")"));
  } else {
    p = calibratedCameraParams(file.sensors.at(size_t(image.sensor)), image.cvCameraFromWorld);
  }
  ParamSet set = paramSetOf(p, source);
  // paramSetOf leaves out values equal to the defaults; a command's defaults (bench renders
  // 1920x1080) must not replace the file's size, nor its framing a glTF camera's eye.
  std::vector<const char*> always = {"size"};
  if (image.gltfCamera >= 0) always.insert(always.end(), {"eye", "up"});
  for (const char* name : always)
    if (!set.has(name)) {
      const ParamSpec& spec = *findCameraParamSpec(name);
      set.set(spec, *spec.access.get(p), source);
    }
  return set;
}

std::string renderNameOf(const std::string& imageName, const std::string& extension) {
  return std::filesystem::path(imageName).replace_extension(extension).generic_string();
}

}  // namespace aperture::app
