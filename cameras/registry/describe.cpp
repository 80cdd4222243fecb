#include "cameras/registry/describe.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "cameras/models/base.h"
#include "cameras/registry/registry.h"
#include "cameras/schema/conventions.h"
#include "cameras/schema/param_schema.h"

namespace aperture {

namespace {
std::string vec(const glm::dvec3& v) {
  char buf[128];
  // Adding 0 turns −0 into +0 for printing.
  std::snprintf(buf, sizeof buf, "(%.9g, %.9g, %.9g)", v.x + 0.0, v.y + 0.0, v.z + 0.0);
  return buf;
}

/// A 4x4 matrix as the EXR header stores it: Imath rows, applied as p' = p·M. Imath's [i][j]
/// is GLM's m[i][j] of the column-vector matrix (the transpose, indexed the other way round).
void printRowVectorMatrix(std::ostream& s, const glm::dmat4& m) {
  for (int i = 0; i < 4; ++i) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "    [%.9g, %.9g, %.9g, %.9g]\n", m[i][0] + 0.0, m[i][1] + 0.0,
                  m[i][2] + 0.0, m[i][3] + 0.0);
    s << buf;
  }
}

/// The standard attributes and the projection attributes `aperture render` writes to the EXR.
void describeExrHeader(std::ostream& s, const CameraDescription& desc) {
  s << "OpenEXR header:\n  pixelAspectRatio " << desc.pixelAspectRatio << ", screenWindowCenter ("
    << desc.screenWindowCenter.x + 0.0 << ", " << desc.screenWindowCenter.y + 0.0
    << "), screenWindowWidth " << desc.screenWindowWidth << "\n";
  s << "  worldToCamera (p' = p·M; camera space left-handed: +x right, +y up, +z forward):\n";
  printRowVectorMatrix(s, desc.exrCameraFromWorld);
  if (desc.ndcFromWorld) {
    s << "  worldToNDC (p' = p·M, then divide by w; NDC (0, 0) top-left, (1, 1) bottom-right):\n";
    printRowVectorMatrix(s, *desc.ndcFromWorld);
  } else {
    s << "  worldToNDC: none ("
      << (desc.lens ? "a lens with distortion is not a projective map"
                    : "a panorama has no projective matrix")
      << ")\n";
  }
  if (const auto& e = desc.equirect)
    s << "  aperture.equirect.longitudeRange (" << e->longitudeDeg.x << ", " << e->longitudeDeg.y
      << ") deg, aperture.equirect.latitudeRange (" << e->latitudeDeg.x << ", " << e->latitudeDeg.y
      << ") deg\n";
  if (const auto& f = desc.fisheye)
    s << "  aperture.fisheye.mapping equidistant, aperture.fisheye.fov " << f->fovDeg
      << " deg, aperture.fisheye.center (" << f->centerPx.x << ", " << f->centerPx.y
      << ") px, aperture.fisheye.radius " << f->radiusPx << " px\n";
}
}  // namespace

std::string describeParameters(const CameraParams& params) {
  std::ostringstream s;
  s << "parameters (" << params.type << "; from the schema, docs/cameras.md):\n";
  for (const ParamSpec* spec : findCameraModel(params.type).params) {
    const std::optional<ParamValue> v = spec->access.get(params);
    s << "  " << spec->name << " = "
      << (v ? formatParamValue(*v) : "not given: " + spec->defaultText());
    if (*spec->unit) s << "  [" << spec->unit << "]";
    s << "\n";
  }
  return s.str();
}

std::string describeCamera(const CameraParams& params, double nearDist, double farDist) {
  const auto cam = makeCameraModel(params);
  const CameraDescription desc = cam->describe();
  const bool planarPerspective = params.type == "perspective" || params.type == "thinlens";
  const bool parallel = params.type == "orthographic" || params.type == "oblique";
  if (nearDist < 0) nearDist = planarPerspective ? cam->d() : 0.0;
  if (farDist < 0) {
    farDist = params.at ? 2.0 * glm::length(*params.at - params.eye)
                        : 10.0 * (parallel ? std::max(cam->vw(), cam->vh()) : cam->d());
    farDist = std::max(farDist, 10.0 * nearDist);
  }
  std::ostringstream s;
  s.precision(9);
  s << "camera " << desc.type << ", " << desc.width << "x" << desc.height << " pixels, spp "
    << desc.spp << "\n";
  s << describeParameters(params);
  s << "frame (world):\n  e = " << vec(desc.eye) << "\n  U = " << vec(desc.u)
    << "\n  V = " << vec(desc.v) << "\n  W = " << vec(desc.w) << "  (W points backwards)\n";
  if (planarPerspective || parallel) {
    s << "image plane: d = " << desc.d << ", viewport vw x vh = " << desc.vw << " x " << desc.vh
      << (parallel ? " (world units; d unused)" : "") << ", shift = (" << cam->shift().x << ", "
      << cam->shift().y << ") viewports\n";
  }
  if (planarPerspective) {
    const ConventionSummary c =
        toConventions({desc.d, desc.vw, desc.vh, cam->shift()}, desc.width, desc.height);
    s << "conventions:\n"
      << "  fov horizontal " << c.fovXDeg << " deg, vertical " << c.fovYDeg << " deg, diagonal "
      << c.fovDiagonalDeg << " deg (centred window)\n"
      << "  pbrt-v4 fov (shorter axis) " << c.pbrtFovDeg << " deg\n"
      << "  Mitsuba 3 fov " << c.mitsubaFovXDeg << " deg (fov_axis x)\n"
      << "  35 mm equivalent focal length " << c.focal35DiagonalMm
      << " mm (by the diagonal of 36 x 24 mm), " << c.focal35HorizontalMm
      << " mm (by the 36 mm width)\n"
      << "  OpenCV fx " << c.fx << ", fy " << c.fy << ", cx " << c.cx << ", cy " << c.cy
      << " (pixels, y down, pixel centres at integers)\n";
  }
  if (desc.lens) {
    s << "lens: " << desc.lens->model << ",";
    for (size_t k = 0; k < desc.lens->params.size(); ++k)
      s << " " << desc.lens->paramNames[k] << " = " << desc.lens->params[k];
    s << " (pixel centres " << desc.lens->pixelCentre << ")\n";
  }
  for (const auto& [k, v] : desc.extra) s << "  " << k << " = " << v << "\n";
  describeExrHeader(s, desc);
  const ViewVolume vv = cam->viewVolume(nearDist, farDist);
  s << "view volume: " << vv.kindName() << ", "
    << (vv.kind == ViewVolume::Kind::AllSpace ? "distance" : "depth along -W") << " from "
    << nearDist << " to " << farDist << "\n";
  const char* names[8] = {"near bottom-left", "near bottom-right", "near top-right",
                          "near top-left",    "far bottom-left",   "far bottom-right",
                          "far top-right",    "far top-left"};
  if (vv.kind == ViewVolume::Kind::AllSpace) s << "  corners of the cube around the far sphere:\n";
  for (int c = 0; c < 8; ++c)
    s << "  " << (vv.kind == ViewVolume::Kind::AllSpace ? "corner" : names[c])
      << (vv.kind == ViewVolume::Kind::AllSpace ? " " + std::to_string(c) : std::string()) << " "
      << vec(vv.corners[c]) << "\n";
  return s.str();
}

}  // namespace aperture
