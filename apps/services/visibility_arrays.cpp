#include "apps/services/visibility_arrays.h"

#include <cstdint>

namespace aperture::app {

namespace {

/// NumPy's dtype string of the element types the visibility arrays use.
template <class T>
const char* dtypeOf();
template <>
const char* dtypeOf<uint32_t>() {
  return "<u4";
}
template <>
const char* dtypeOf<uint64_t>() {
  return "<u8";
}
template <>
const char* dtypeOf<int32_t>() {
  return "<i4";
}

/// A one-dimensional array over `values` (not copied).
template <class T>
NpzArray vectorArray(const std::string& name, const std::vector<T>& values) {
  return {name, dtypeOf<T>(), {values.size()}, values.data(), values.size() * sizeof(T)};
}

/// NAME_indptr and NAME_indices of `rows`.
void appendSparseRows(std::vector<NpzArray>& out, const std::string& name, const SparseRows& rows) {
  out.push_back(vectorArray(name + "_indptr", rows.indptr));
  out.push_back(vectorArray(name + "_indices", rows.indices));
}

}  // namespace

std::vector<NpzArray> faceVisibilityArrays(const FaceVisibility& v) {
  std::vector<NpzArray> out = {vectorArray("face_view_count", v.viewCount),
                               vectorArray("face_pixels", v.pixels),
                               vectorArray("best_view", v.bestView)};
  appendSparseRows(out, "camera_faces", v.cameraFaces);
  appendSparseRows(out, "face_cameras", v.faceCameras);
  return out;
}

std::vector<NpzArray> pointVisibilityArrays(const PointVisibility& v) {
  std::vector<NpzArray> out;
  appendSparseRows(out, "point_cameras", v.pointCameras);
  return out;
}

}  // namespace aperture::app
