#pragma once
// Layered hits (--layers K --deep) as an OpenEXR deep scanline file beside the flat EXR.
#include <string>

#include "core/aov/framebuffer.h"
#include "core/exr/exr.h"

namespace aperture {

/// Where the deep file of the EXR `exrPath` goes: its path with ".deep.exr" for ".exr"
/// ("out/render.exr" -> "out/render.deep.exr").
std::string deepLayersPath(const std::string& exrPath);

/// Writes the layered hits of `fb` (fb.layers = K >= 1) to `path` as a deep scanline EXR: each
/// pixel holds one sample per surface found (0..K), nearest first, in the channels Z and ZBack
/// (float, both the surface's planar depth: a point sample in the sense of OpenEXR's
/// "Interpreting Deep Pixels"), T (float, distance from the ray origin), primID and geomID
/// (UINT). The header has the attributes of writeExr for `meta` plus "aperture.layers" (int,
/// K). ZIPS compression (one scanline a block; OpenEXR 3.1's deep files allow none, rle and
/// zips only). Written to a temporary
/// file and renamed, like writeExr. Throws Error naming `path`.
void writeDeepLayersExr(const std::string& path, const Framebuffer& fb, const ExrMetadata& meta);

/// Reads a file written by writeDeepLayersExr into a Framebuffer holding only the layers
/// (layers = "aperture.layers", else the largest sample count): a pixel's samples fill layers
/// 0.. in file order, the layers past them keep the miss values (+inf, 0xFFFFFFFF). Throws
/// Error naming `path` for an unreadable or incomplete file, or more samples than layers.
Framebuffer readDeepLayersExr(const std::string& path);

}  // namespace aperture
