#pragma once
// The PLY header as the loader reads it. The loader (core/mesh/ply.cpp) and the memory estimate
// (apps/services/limits.cpp) both use readPlyHeader, so they see the same elements, counts and
// layout.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace aperture {

/// Scalar types of PLY properties (both spellings map here: "uchar" and "uint8", ...).
enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

/// Bytes of one binary value of type `t`.
inline size_t plyTypeSize(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
      return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
      return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 0;
}

/// One `property` line: a scalar, or a list with its count type and item type.
struct PlyProperty {
  std::string name;
  bool list = false;
  PlyType type = PlyType::Float32;     ///< value type (list items for a list)
  PlyType countType = PlyType::UInt8;  ///< list count type
};

/// One `element` line and the properties that follow it.
struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> props;
  size_t line = 0;  ///< header line number, for messages
};

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

/// A parsed header: the format, the elements in file order and where the data starts.
struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  size_t dataOffset = 0;  ///< byte offset of the first data byte (just after end_header)
  size_t dataLine = 1;    ///< line number of the first data line (ASCII)
};

/// Reads the header at the start of `data` (`size` bytes; only the header needs to be there,
/// so a prefix of the file will do). Throws Error naming `path` and the line for a first line
/// that is not "ply", no end_header within 1 MiB, a missing or unknown format, a bad element
/// or property line, an unknown type or a duplicate element. Counts are not checked against
/// the data (checkPlyCountsFitData does that).
PlyHeader readPlyHeader(const std::string& path, const char* data, size_t size);

/// Fewest bytes one item of `e` can take: binary, its scalars and list counts; ASCII, two
/// characters (a digit and a separator) per property. 0 for an element without properties.
uint64_t plyMinItemBytes(PlyFormat format, const PlyElement& e);

struct Mesh;
struct LoadOptions;

/// Which readers loadPlyFromMemory uses for binary data: the parallel ones where the items
/// have a fixed size (the default), or only the serial ones (APERTURE_PLY_SERIAL=1 in the
/// environment). Both give the same mesh, bit for bit, and the same errors.
enum class PlyParsing { Parallel, Serial };

/// loadPlyFromMemory (core/mesh/mesh.h) with the readers chosen by `parsing`, not the environment.
Mesh loadPlyFromMemory(const char* data, size_t size, const std::string& name,
                       const LoadOptions& options, PlyParsing parsing);

/// Throws Error naming `path`, the element and its line when the elements' counts need more
/// than the `dataBytes` bytes that follow the header (checked before anything is allocated).
void checkPlyCountsFitData(const std::string& path, const PlyHeader& header, uint64_t dataBytes);

}  // namespace aperture
