// The conventions of calibrated camera sources: names, the one pixel-centre conversion and the
// one axis conversion (see calibration.h).
#include "cameras/lenses/calibration.h"

#include <cmath>
#include <vector>

#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {

struct AxisConventionName {
  AxisConvention convention;
  const char* name;
};
constexpr AxisConventionName kAxisConventionNames[] = {
    {AxisConvention::OpenCV, "opencv"},
    {AxisConvention::OpenGL, "opengl"},
    {AxisConvention::Blender, "blender"},
};

// Tolerance of the rotation check: |R·Rᵀ − I| per entry and |det R − 1|. Calibration files
// carry rotations printed to float precision (NeRF's synthetic scenes) or better.
constexpr double kRotationTolerance = 1e-6;

// glCameraFromWorld as cvCameraFromWorld or back (OpenGL and Blender camera axes to OpenCV's):
// x stays, y and z flip, so rows 1 and 2 are negated (exactly). Its own inverse.
glm::dmat4 flipCameraYZ(glm::dmat4 cameraFromWorld) {
  for (int c = 0; c < 4; ++c) {
    cameraFromWorld[c][1] = -cameraFromWorld[c][1];
    cameraFromWorld[c][2] = -cameraFromWorld[c][2];
  }
  return cameraFromWorld;
}

// The inverse of a rigid transform [R t; 0 1]: [Rᵀ −Rᵀt; 0 1]. The rotation part is exact
// (a transpose); the translation is rounded once per component.
glm::dmat4 rigidInverse(const glm::dmat4& m) {
  glm::dmat4 inv(1.0);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) inv[c][r] = m[r][c];
  for (int r = 0; r < 3; ++r)
    inv[3][r] = -(inv[0][r] * m[3][0] + inv[1][r] * m[3][1] + inv[2][r] * m[3][2]);
  return inv;
}

void checkRigid(const glm::dmat4& pose, const std::string& context) {
  if (pose[0][3] != 0 || pose[1][3] != 0 || pose[2][3] != 0 || pose[3][3] != 1)
    throw Error(cat(context, ": the last row of the pose is (", pose[0][3], ", ", pose[1][3], ", ",
                    pose[2][3], ", ", pose[3][3], "), expected (0, 0, 0, 1)"));
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r)
      if (!std::isfinite(pose[c][r]))
        throw Error(cat(context, ": pose entry (row ", r, ", column ", c, ") is ", pose[c][r]));
  const glm::dmat3 rot(pose);
  const glm::dmat3 gram = glm::transpose(rot) * rot;
  double worst = 0;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r)
      worst = std::max(worst, std::abs(gram[c][r] - (r == c ? 1.0 : 0.0)));
  const double det = glm::determinant(rot);
  if (worst > kRotationTolerance || std::abs(det - 1) > kRotationTolerance)
    throw Error(cat(context, ": the rotation part of the pose is not a rotation (|RᵀR − I| = ",
                    worst, ", det = ", det, "; expected orthonormal to ", kRotationTolerance,
                    " with determinant +1)"));
}

}  // namespace

const char* axisConventionName(AxisConvention c) {
  for (const AxisConventionName& n : kAxisConventionNames)
    if (n.convention == c) return n.name;
  throw Error("internal: unknown axis convention");
}

AxisConvention parseAxisConvention(const std::string& name) {
  std::vector<std::string> names;
  for (const AxisConventionName& n : kAxisConventionNames) {
    if (toLowerAscii(name) == n.name) return n.convention;
    names.emplace_back(n.name);
  }
  throw Error(cat("unknown axis convention '", name, "' (known: ", join(names, ", "), ")",
                  didYouMean(name, names)));
}

const char* pixelCentreName(PixelCentre c) {
  return c == PixelCentre::HalfInteger ? "half-integer" : "integer";
}

glm::dmat4 cvCameraFromWorldOf(const glm::dmat4& pose, AxisConvention from,
                               bool poseIsWorldFromCamera, const std::string& context) {
  checkRigid(pose, context);
  // The camera in `from` axes.
  const glm::dmat4 cameraFromWorld = poseIsWorldFromCamera ? rigidInverse(pose) : pose;
  return from == AxisConvention::OpenCV ? cameraFromWorld : flipCameraYZ(cameraFromWorld);
}

glm::dmat4 poseInConvention(const glm::dmat4& cvCameraFromWorld, AxisConvention to,
                            bool poseIsWorldFromCamera) {
  // The camera in `to` axes.
  const glm::dmat4 cameraFromWorld =
      to == AxisConvention::OpenCV ? cvCameraFromWorld : flipCameraYZ(cvCameraFromWorld);
  return poseIsWorldFromCamera ? rigidInverse(cameraFromWorld) : cameraFromWorld;
}

}  // namespace aperture
