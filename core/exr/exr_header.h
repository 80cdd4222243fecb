#pragma once
// The EXR header aperture writes, for the EXR writers of core (exr.cpp, exr_deep.cpp); kept out
// of core/exr/exr.h so that OpenEXR's headers stay private to core.
#include <OpenEXR/ImfHeader.h>

#include <string>

#include "core/exr/exr.h"

namespace aperture {

/// A header of `width` x `height` pixels with the attributes writeExr documents for `meta`
/// (screen window, camera matrices and parameters, render time, strings), no channels, default
/// compression. Throws Error naming `path` for a pixel aspect ratio OpenEXR refuses.
Imf::Header exrHeaderFor(const std::string& path, int width, int height, const ExrMetadata& meta);

}  // namespace aperture
