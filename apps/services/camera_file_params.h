#pragma once
// Camera files on the command line and in job files: `--cameras PATH` with `--image NAME`,
// and a job's "cameras": {"from": PATH, "images": [...]}. Each image of the file becomes the
// parameters of a calibrated camera (cameras/models/calibrated.h), so it is checked, described and
// rendered like any other camera; a glTF camera becomes a perspective or orthographic camera
// (gltfCameraParams).
#include <optional>
#include <string>
#include <vector>

#include "cameras/files/camera_file.h"
#include "cameras/schema/param_schema.h"

namespace aperture::app {

/// What --cameras accepts (the help line of render, camera, bench, tradeoff and batch).
inline constexpr const char* kCameraFileHelp =
    "Camera file: a COLMAP model folder (text or binary), a transforms.json (nerfstudio, NeRF, "
    "instant-ngp), an OpenCV JSON/YAML or a glTF .gltf/.glb (its camera nodes)";

/// The images of `file` named in `names`, in the order of `names` (all of them, in the file's
/// order, when `names` is empty). An unknown name is an Error naming `flag`, the file and the
/// closest image name.
std::vector<const CalibratedImage*> selectImages(const CameraFile& file,
                                                 const std::vector<std::string>& names,
                                                 const std::string& flag);

/// The image size a front end gives the cameras of a glTF file, which carry none: --size, a
/// job's "size", Python's width / height. Either side may be missing.
struct GltfImageSize {
  std::optional<int> width, height;
  /// The height when neither side is given (the command's default size's).
  int defaultHeight = CameraParams().height;
};

/// The parameters of a glTF camera (the one owner of its projection; its axes are
/// gltfCvCameraFromWorld's, cameras/files/camera_file.h), posed by `cvCameraFromWorld`:
///  - pose: eye the node's origin, view along its −Z, up its +Y;
///  - perspective: fov = yfov (vertical, fov_axis y; the horizontal extent follows the image,
///    square pixels); clip = (znear, zfar), planar depths as glTF's projection has them (no
///    zfar: far = the largest float, no far clipping);
///  - orthographic: viewport = (2·xmag, 2·ymag), the full extents; znear and zfar are not
///    applied (the orthographic model has no clipping);
///  - image size: both sides given are used; one side given sets the other from the camera's
///    aspect (aspectRatio, or xmag / ymag), rounded to the nearest pixel; none given: the height
///    is size.defaultHeight and the width follows the aspect. A perspective camera without
///    aspectRatio needs both sides. Both sides given must have the aspect to within a pixel
///    of width, else Error (the view would be stretched or cut).
/// Errors name `context` ("scene.glb camera 'Camera' (/nodes/3)").
CameraParams gltfCameraParams(const SceneCamera& camera, const glm::dmat4& cvCameraFromWorld,
                              const GltfImageSize& size, const std::string& context);

/// The camera parameters of one image, each with the source "PATH image 'NAME'": a calibrated
/// camera, or for a glTF camera gltfCameraParams at `gltfSize`. The image size is always in
/// the set (so a command's default size never replaces the file's).
ParamSet imageParamSet(const CameraFile& file, const CalibratedImage& image,
                       const GltfImageSize& gltfSize = {});

/// Where an image's render goes below an output directory: its name with the extension
/// replaced by `extension`, subfolders kept ("left/0001.jpg" -> "left/0001.exr").
std::string renderNameOf(const std::string& imageName, const std::string& extension);

}  // namespace aperture::app
