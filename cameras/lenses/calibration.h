#pragma once
// Calibrated cameras as their source files give them: a sensor (image size, lens, pixel
// convention) and, per image, a world-to-camera pose. The conventions of the sources are
// written here once:
//  - pixel centres: COLMAP, nerfstudio and instant-ngp put the centre of pixel (row i,
//    column j) at (j + 0.5, i + 0.5), OpenCV at (j, i) (sourcePixelOfRaster);
//  - camera axes: COLMAP and OpenCV x right, y down, z forward; OpenGL, nerfstudio,
//    instant-ngp and Blender x right, y up, z backwards (cvCameraFromWorldOf).
// Internally every pose is world-to-camera in OpenCV axes and every lens in COLMAP's pixel
// convention plus the PixelCentre of its source.
//
// Names of transforms: aFromB maps B's coordinates to A's (compositions read right to left),
// and a camera space carries its axes as a prefix, one per AxisConvention: cvCamera (OpenCV:
// x right, y down, z forward), glCamera (OpenGL and Blender: x right, y up, z backwards);
// exrCamera is OpenEXR's (x right, y up, z forward; CameraDescription::exrCameraFromWorld in
// core/engine/camera.h). A pose as a source gives it, in the axes its `convention` names, is
// sourceCameraFromWorld / worldFromSourceCamera (CameraParams, cameras/schema/params.h).
#include <glm/glm.hpp>
#include <string>

#include "cameras/lenses/lens_model.h"

namespace aperture {

/// Where a source puts the centre of pixel (row i, column j).
enum class PixelCentre {
  HalfInteger,  ///< (j + 0.5, i + 0.5): COLMAP, nerfstudio, instant-ngp, aperture's raster
  Integer,      ///< (j, i): OpenCV
};

/// Camera-space axes of a source.
enum class AxisConvention {
  OpenCV,   ///< x right, y down, z forward (COLMAP, OpenCV)
  OpenGL,   ///< x right, y up, z backwards (nerfstudio, instant-ngp)
  Blender,  ///< as OpenGL (Blender's camera looks down its local −z with +y up)
};

/// "opencv", "opengl", "blender"; parse throws Error naming the text (with "did you mean").
const char* axisConventionName(AxisConvention c);
AxisConvention parseAxisConvention(const std::string& name);
const char* pixelCentreName(PixelCentre c);  ///< "half-integer", "integer"

/// The one pixel-centre conversion: aperture's raster position (pixel (i, j) centre at
/// (j + ½, i + ½)) in a source's pixel coordinates, and back. The raster and the half-integer
/// sources agree; OpenCV's pixel (i, j) centre (j, i) sits half a pixel up and left of the
/// raster's. Inline: the direction tables convert every pixel.
inline glm::dvec2 sourcePixelOfRaster(const glm::dvec2& raster, PixelCentre centre) {
  return centre == PixelCentre::HalfInteger ? raster : raster - glm::dvec2(0.5);
}
inline glm::dvec2 rasterOfSourcePixel(const glm::dvec2& sourcePixel, PixelCentre centre) {
  return centre == PixelCentre::HalfInteger ? sourcePixel : sourcePixel + glm::dvec2(0.5);
}

/// The one axis conversion: a source's pose (cameraFromWorld, or worldFromCamera when
/// `poseIsWorldFromCamera`) in its axes, as cvCameraFromWorld. Throws Error (naming
/// `context`) when the rotation part is not a rotation (orthonormal to 1e-6, determinant +1)
/// or the last row is not (0, 0, 0, 1).
glm::dmat4 cvCameraFromWorldOf(const glm::dmat4& pose, AxisConvention from,
                               bool poseIsWorldFromCamera, const std::string& context);
/// The inverse: cvCameraFromWorld as a pose in `to` axes (cameraFromWorld, or worldFromCamera
/// when `poseIsWorldFromCamera`).
glm::dmat4 poseInConvention(const glm::dmat4& cvCameraFromWorld, AxisConvention to,
                            bool poseIsWorldFromCamera);

/// One physical camera: image size, lens (COLMAP parameter order) and the pixel convention
/// its principal point is given in.
struct CalibratedSensor {
  int width = 0, height = 0;
  Lens lens{LensModelId::Pinhole, {1, 1, 0, 0}};
  PixelCentre pixelCentre = PixelCentre::HalfInteger;
  bool operator==(const CalibratedSensor& o) const {
    return width == o.width && height == o.height && lens == o.lens && pixelCentre == o.pixelCentre;
  }
};

}  // namespace aperture
