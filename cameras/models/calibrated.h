#pragma once
// The calibrated camera model ("calibrated"): a lens after COLMAP (cameras/lenses/lens_model.h) in
// its source's pixel convention, posed by a world-to-camera or camera-to-world matrix in
// OpenCV, OpenGL or Blender axes, or by eye / at / up like the lecture cameras. Camera files
// (cameras/files/camera_file.h) become these parameters; they are the parameters' one owner.
#include <cstdint>
#include <glm/glm.hpp>
#include <optional>
#include <vector>

#include "cameras/geometry/frame.h"
#include "cameras/lenses/calibration.h"
#include "cameras/schema/params.h"
#include "core/engine/camera.h"

namespace aperture {

/// The sensor of calibrated parameters: image size, the lens built from lens_model,
/// intrinsics (fx, fy, cx, cy; single-focal models need fx == fy) and distortion, and the
/// pixel convention. Throws Error naming the parameter for a wrong count or value.
CalibratedSensor calibratedSensorOf(const CameraParams& p);

/// Whether a calibrated camera with this lens reads its rays from a direction table
/// (cameras/lenses/direction_table.h): a distorted lens. An undistorted pinhole computes them.
bool readsDirectionTable(const Lens& lens);

/// At most how many bytes of direction tables cameras of `cameras`, made one after the other,
/// hold at once (DirectionTable::peakBytes of the calibrated ones that read a table): for
/// --max-memory. Throws Error as calibratedSensorOf for a calibrated camera's bad lens.
uint64_t directionTableBytes(const std::vector<CameraParams>& cameras);

/// World-to-camera in OpenCV axes: from world_to_camera / camera_to_world (in `convention`
/// axes) when given, else from the frame of eye / at / up (x = U, y = −V, z = −W).
glm::dmat4 calibratedWorldToCamera(const CameraParams& p);

/// The lecture frame of a world-to-camera pose in OpenCV axes: e = −Rᵀt, U = x, V = −y, W = −z
/// (the rows of R).
CameraFrame frameOfWorldToCamera(const glm::dmat4& worldToCameraCv);

/// Calibrated parameters (type "calibrated") for one image of a camera file: every number is
/// carried over exactly.
CameraParams calibratedCameraParams(const CalibratedSensor& sensor,
                                    const glm::dmat4& worldToCameraCv);

/// A camera as a calibrated camera file holds it: sensor and world-to-camera (OpenCV axes).
struct CalibratedView {
  CalibratedSensor sensor;
  glm::dmat4 worldToCamera{1.0};
};

/// The calibrated form of a described camera: a calibrated camera as it is; a pinhole
/// perspective camera (shifted or not) as PINHOLE with fx = W·d/vw, fy = H·d/vh and the
/// principal point of its image window (COLMAP's pixel convention). Nothing for the models no
/// calibrated camera expresses (parallel projections, panoramas, a thin lens).
std::optional<CalibratedView> calibratedViewOf(const CameraDescription& c);
/// (For camera parameters, see calibratedViewOf in cameras/registry/registry.h.)

/// Row-major 16 numbers of a matrix, and back (GLM is column-major).
std::vector<double> rowMajor(const glm::dmat4& m);
glm::dmat4 matrixOfRowMajor(const std::vector<double>& v);

}  // namespace aperture
