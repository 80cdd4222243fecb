#pragma once
// NumPy .npz archives (np.savez's layout: a zip of .npy members, stored without compression;
// zip64 records where a member or the archive passes 4 GiB), written atomically. The .npy
// header is the one of core/io/npy.h.
#include <cstdint>
#include <string>
#include <vector>

namespace aperture {

/// One array of an archive: `name` becomes the member "name.npy". `descr` is NumPy's dtype
/// string ('<u4', '<u8', '<i4', '<f4', '<f8', '<U12', ...), `shape` C order; `data` holds
/// exactly the bytes the shape and dtype make (not copied: must outlive the write).
struct NpzArray {
  std::string name;
  std::string descr;
  std::vector<uint64_t> shape;
  const void* data = nullptr;
  uint64_t bytes = 0;
};

/// An array of strings as NumPy's fixed-width unicode dtype '<U{n}' (n the longest string's
/// code points, at least 1): UTF-32LE, each padded with zeros. `storage` receives the bytes
/// the returned NpzArray points to. Throws Error for a string that is not valid UTF-8.
NpzArray npzStringArray(const std::string& name, const std::vector<std::string>& strings,
                        std::vector<uint8_t>& storage);

/// How writeNpz lays out the archive.
struct NpzOptions {
  /// Zip64 records for every member and the end of the archive even where the sizes and
  /// offsets fit 32 bits (tests: the zip64 layout without writing 4 GiB).
  bool forceZip64 = false;
};

/// Writes `arrays` to `path` as an .npz (atomically: a failure leaves no file). Throws Error
/// naming the file for a duplicate or empty name, bytes that do not match shape and dtype,
/// or an I/O failure.
void writeNpz(const std::string& path, const std::vector<NpzArray>& arrays,
              const NpzOptions& options = {});

/// One member read back by readNpz: its dtype string, shape and raw little-endian bytes.
struct NpzMember {
  std::string descr;
  std::vector<uint64_t> shape;
  std::vector<uint8_t> data;
};

/// Reads an .npz with stored (uncompressed) members, as writeNpz writes them, zip64 included:
/// name (without ".npy") -> member, in archive order. Throws Error naming the file and the
/// member for anything malformed or compressed. (Tools and tests; NumPy reads these too.)
std::vector<std::pair<std::string, NpzMember>> readNpz(const std::string& path);

}  // namespace aperture
