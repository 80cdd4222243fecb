#pragma once
// The arrays of a visibility result under the names `aperture visibility` writes to its .npz
// and Python's face_visibility / point_visibility return (docs/visibility.md): the one owner
// of those names, dtypes and shapes.
#include <string>
#include <vector>

#include "core/io/npz.h"
#include "core/queries/visibility.h"

namespace aperture::app {

/// face_view_count (uint32, F), face_pixels (uint64, F), best_view (int32, F), and the CSR
/// pairs camera_faces_indptr (uint64, C + 1) / camera_faces_indices (uint32) and
/// face_cameras_indptr (uint64, F + 1) / face_cameras_indices (uint32). The arrays point into
/// `v`, which must outlive them.
std::vector<NpzArray> faceVisibilityArrays(const FaceVisibility& v);

/// point_cameras_indptr (uint64, N + 1) / point_cameras_indices (uint32), pointing into `v`.
std::vector<NpzArray> pointVisibilityArrays(const PointVisibility& v);

}  // namespace aperture::app
