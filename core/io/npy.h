#pragma once
// The NumPy .npy format 1.0 header: the one owner of its layout, used by the single-AOV
// dataset files (core/io/dataset_image.cpp) and the .npz archives (core/io/npz.cpp).
#include <cstdint>
#include <string>
#include <vector>

namespace aperture {

/// The header of a C-order array of dtype `descr` ('<f4', '<u8', '<U12', ...) and `shape`:
/// magic, version 1.0, the length and the dict, padded with spaces and a newline so the data
/// starts at a multiple of 64 bytes.
std::string npyHeader(const std::string& descr, const std::vector<uint64_t>& shape);

/// A parsed .npy header.
struct NpyHeader {
  std::string descr;
  bool fortranOrder = false;
  std::vector<uint64_t> shape;
  size_t dataOffset = 0;  ///< bytes from the start of the file to the first data byte
};

/// Parses the header at the start of `data` (`size` bytes), versions 1.0 to 3.0. Throws Error
/// naming `what` (a file, or "ARCHIVE member NAME") for anything malformed.
NpyHeader parseNpyHeader(const uint8_t* data, size_t size, const std::string& what);

/// Bytes of one item of `descr` ('<f4' 4, '<U12' 48, ...); Error for an unknown dtype.
size_t npyItemBytes(const std::string& descr, const std::string& what);

}  // namespace aperture
