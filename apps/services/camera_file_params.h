#pragma once
// Camera files on the command line and in job files: `--cameras PATH` with `--image NAME`,
// and a job's "cameras": {"from": PATH, "images": [...]}. Each image of the file becomes the
// parameters of a calibrated camera (cameras/models/calibrated.h), so it is checked, described and
// rendered like any other camera.
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "cameras/schema/param_schema.h"

namespace aperture::app {

/// What --cameras accepts (the help line of render, camera, bench, tradeoff and batch).
inline constexpr const char* kCameraFileHelp =
    "Camera file: a COLMAP model folder (text or binary), a transforms.json (nerfstudio, NeRF, "
    "instant-ngp) or an OpenCV JSON/YAML";

/// The images of `file` named in `names`, in the order of `names` (all of them, in the file's
/// order, when `names` is empty). An unknown name is an Error naming `flag`, the file and the
/// closest image name.
std::vector<const CalibratedImage*> selectImages(const CameraFile& file,
                                                 const std::vector<std::string>& names,
                                                 const std::string& flag);

/// The calibrated camera parameters of one image, each with the source "PATH image 'NAME'".
ParamSet imageParamSet(const CameraFile& file, const CalibratedImage& image);

/// Where an image's render goes below an output directory: its name with the extension
/// replaced by `extension`, subfolders kept ("left/0001.jpg" -> "left/0001.exr").
std::string renderNameOf(const std::string& imageName, const std::string& extension);

}  // namespace aperture::app
