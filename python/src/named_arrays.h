#pragma once
// Named one-dimensional arrays (core/io/npz.h's NpzArray, as apps/services/visibility_arrays.h
// names them) handed to NumPy without a copy: the same names and dtypes the .npz of `aperture
// visibility` holds.
#include <nanobind/nanobind.h>

#include <memory>
#include <vector>

#include "core/io/npz.h"

namespace aperture::python {

/// name -> NumPy array of each of `arrays` (dtypes '|u1', '<u2', '<u4', '<u8', '<i4', '<f4',
/// '<f8'), pointing into the object `owner` holds, which a capsule keeps alive until the last array
/// is gone. Throws Error for another dtype.
nanobind::dict namedArrays(std::shared_ptr<const void> owner, const std::vector<NpzArray>& arrays);

}  // namespace aperture::python
