#pragma once
// Little-endian bytes in and out: the one place that splits a scalar into bytes and assembles
// it again, for the binary formats read and written here (PLY, .npy and .npz, PFM, COLMAP's
// binary models). Byte by byte, so the host's byte order and alignment do not matter.
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace aperture {

/// The unsigned integer of the `bytes` (at most 8) little-endian bytes at `p`.
inline uint64_t loadLittleEndianBytes(const void* p, size_t bytes) {
  const auto* b = static_cast<const unsigned char*>(p);
  uint64_t v = 0;
  for (size_t k = 0; k < bytes; ++k) v |= uint64_t(b[k]) << (8 * k);
  return v;
}

/// The scalar T (integer or floating point, 1, 2, 4 or 8 bytes) stored little-endian at `p`.
template <typename T>
T loadLittleEndian(const void* p) {
  static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4 || sizeof(T) == 8, "a scalar");
  const uint64_t bits = loadLittleEndianBytes(p, sizeof(T));
  // The value's bits are the low sizeof(T) bytes of `bits`, copied from a type of that size.
  T value;
  if constexpr (sizeof(T) == 8) {
    std::memcpy(&value, &bits, 8);
  } else if constexpr (sizeof(T) == 4) {
    const auto narrow = uint32_t(bits);
    std::memcpy(&value, &narrow, 4);
  } else if constexpr (sizeof(T) == 2) {
    const auto narrow = uint16_t(bits);
    std::memcpy(&value, &narrow, 2);
  } else {
    const auto narrow = uint8_t(bits);
    std::memcpy(&value, &narrow, 1);
  }
  return value;
}

/// Appends the little-endian bytes of the scalar `value` to `out` (a std::string or a
/// std::vector<char>).
template <typename T, typename Bytes>
void appendLittleEndian(Bytes& out, T value) {
  static_assert(sizeof(T) <= 8, "a scalar");
  uint64_t bits = 0;
  if constexpr (sizeof(T) == 8) {
    std::memcpy(&bits, &value, 8);
  } else if constexpr (sizeof(T) == 4) {
    uint32_t narrow;
    std::memcpy(&narrow, &value, 4);
    bits = narrow;
  } else if constexpr (sizeof(T) == 2) {
    uint16_t narrow;
    std::memcpy(&narrow, &value, 2);
    bits = narrow;
  } else {
    uint8_t narrow;
    std::memcpy(&narrow, &value, 1);
    bits = narrow;
  }
  for (size_t k = 0; k < sizeof(T); ++k) out.push_back(char((bits >> (8 * k)) & 0xffu));
}

/// Stores the `count` 32-bit words at `words` (unaligned: read with memcpy) as 4·count
/// little-endian bytes at `out`. Byte by byte as the rest of this file, with no push_back per
/// byte: GCC merges each word's four byte stores into one store on a little-endian host, so a
/// raster of floats is copied at memory speed.
inline void storeLittleEndianWords(const void* words, size_t count, unsigned char* out) {
  const auto* in = static_cast<const unsigned char*>(words);
  for (size_t k = 0; k < count; ++k) {
    uint32_t w;
    std::memcpy(&w, in + 4 * k, 4);
    out[4 * k] = uint8_t(w);
    out[4 * k + 1] = uint8_t(w >> 8);
    out[4 * k + 2] = uint8_t(w >> 16);
    out[4 * k + 3] = uint8_t(w >> 24);
  }
}

}  // namespace aperture
