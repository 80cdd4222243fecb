#pragma once
// Human-readable camera description for `aperture camera ... --describe`.
#include <string>

#include "cameras/schema/params.h"

namespace aperture {

/// The frame, the image plane in every convention (d·vw·vh, horizontal, vertical and
/// diagonal fov, pbrt-v4, Mitsuba 3, 35 mm equivalent focal length by the diagonal and by the
/// width of a 36 x 24 mm sensor, OpenCV intrinsics), the model's own parameters, the EXR
/// header's camera attributes (pixelAspectRatio, screen window, worldToCamera and worldToNDC
/// as Imath row-vector matrices, or a panorama's projection) and the view volume with the 8
/// corners. nearDist/farDist < 0 pick defaults: near = d for perspective and thin lens, 0
/// otherwise; far = 2·|at − eye| with a look-at point, else 10·d (or 10·max(vw, vh) for
/// parallel cameras). Throws Error as makeCamera.
/// Every parameter the camera's model reads, with its value or, when not given, its default
/// rule and unit: generated from the parameter schema.
std::string describeParameters(const CameraParams& params);

std::string describeCamera(const CameraParams& params, double nearDist = -1, double farDist = -1);

}  // namespace aperture
