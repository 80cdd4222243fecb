// NumPy .npz archives: a zip whose members "NAME.npy" are stored (no compression), as np.savez
// writes them. libzip writes and reads the zip: local headers, central directory, CRC-32, and
// the zip64 records where a member, an offset or the member count passes what 32 (16) bits
// hold. What is chosen here: stored members, the DOS date 1980-01-01 00:00 (archives of the same
// arrays are the same bytes), UTF-8 names (libzip sets bit 11 for a name that is not ASCII).
// The reader takes any method libzip decompresses, so np.savez_compressed's archives too.
#include "core/npz.h"

#include <zip.h>

#include <algorithm>
#include <cstring>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/npy.h"

namespace aperture {

namespace {

constexpr uint16_t kDosDate1980 = (0 << 9) | (1 << 5) | 1;  // year − 1980, month, day
constexpr uint16_t kDosTimeMidnight = 0;
constexpr size_t kMaxNameBytes = 0xffffu;
/// A member is read in pieces of this size: the first holds its .npy header (NumPy's are under
/// 1 KiB), each goes from the cache into the array.
constexpr uint64_t kReadPieceBytes = 256u << 10;

/// `a` × `b`, or false when the product does not fit 64 bits.
bool multiply(uint64_t a, uint64_t b, uint64_t& out) {
  if (b != 0 && a > UINT64_MAX / b) return false;
  out = a * b;
  return true;
}

/// Bytes the array of `descr` and `shape` holds; Error naming `what` when it overflows.
uint64_t arrayBytes(const std::string& descr, const std::vector<uint64_t>& shape,
                    const std::string& what) {
  uint64_t bytes = npyItemBytes(descr, what);
  for (uint64_t d : shape)
    if (!multiply(bytes, d, bytes))
      throw Error(cat(what, ": the shape's byte count does not fit 64 bits"));
  return bytes;
}

void checkArray(const NpzArray& a, const std::string& path, std::set<std::string>& names) {
  if (a.name.empty()) throw Error(cat("cannot write '", path, "': an array has an empty name"));
  if (a.name.find('\0') != std::string::npos || a.name.size() > kMaxNameBytes - 4)
    throw Error(cat("cannot write '", path, "': array name '", a.name,
                    "' holds a NUL byte or is longer than a zip name may be"));
  if (!names.insert(a.name).second)
    throw Error(cat("cannot write '", path, "': array name '", a.name, "' is given twice"));
  const std::string what = cat("'", path, "' array '", a.name, "'");
  const uint64_t expected = arrayBytes(a.descr, a.shape, what);
  if (a.bytes != expected)
    throw Error(cat(what, ": ", a.bytes, " bytes given, dtype '", a.descr, "' and the shape make ",
                    expected));
  if (a.bytes > 0 && a.data == nullptr) throw Error(cat(what, ": no data"));
}

/// libzip's message for an error code of zip_open.
std::string openErrorText(int code) {
  zip_error_t error;
  zip_error_init_with_code(&error, code);
  std::string text = zip_error_strerror(&error);
  zip_error_fini(&error);
  return text;
}

/// An open archive, discarded (nothing written) unless close() succeeded.
class Archive {
 public:
  Archive(const std::string& path, int flags, const std::string& what) {
    int code = 0;
    zip_ = zip_open(path.c_str(), flags, &code);
    if (zip_ == nullptr) throw Error(cat(what, ": ", openErrorText(code)));
  }
  ~Archive() {
    if (zip_ != nullptr) zip_discard(zip_);
  }
  Archive(const Archive&) = delete;
  Archive& operator=(const Archive&) = delete;

  zip_t* get() const { return zip_; }
  std::string errorText() const { return zip_strerror(zip_); }

  /// Writes the archive; Error with libzip's reason on failure.
  void close(const std::string& what) {
    if (zip_close(zip_) != 0) throw Error(cat(what, ": ", errorText()));
    zip_ = nullptr;
  }

 private:
  zip_t* zip_ = nullptr;
};

/// One member opened for reading; libzip checks its CRC-32 when the last byte has been read.
class Member {
 public:
  Member(const Archive& archive, zip_uint64_t index, const std::string& what) : what_(what) {
    file_ = zip_fopen_index(archive.get(), index, 0);
    if (file_ == nullptr) throw Error(cat(what, ": ", archive.errorText()));
  }
  ~Member() {
    if (file_ != nullptr) zip_fclose(file_);
  }
  Member(const Member&) = delete;
  Member& operator=(const Member&) = delete;

  /// Reads exactly `bytes` bytes to `out`.
  void read(uint8_t* out, uint64_t bytes) {
    while (bytes > 0) {
      const zip_int64_t n = zip_fread(file_, out, bytes);
      if (n < 0) throw Error(cat(what_, ": ", zip_file_strerror(file_)));
      if (n == 0) throw Error(cat(what_, ": the data ends ", bytes, " bytes early"));
      out += n;
      bytes -= uint64_t(n);
    }
  }

  /// Reads past the last byte, where libzip compares the CRC-32 (a mismatch is an Error).
  void checkEnd() {
    uint8_t extra = 0;
    const zip_int64_t n = zip_fread(file_, &extra, 1);
    if (n < 0) throw Error(cat(what_, ": ", zip_file_strerror(file_)));
    if (n != 0) throw Error(cat(what_, ": more data than its size says"));
  }

 private:
  zip_file_t* file_ = nullptr;
  const std::string& what_;
};

std::pair<std::string, NpzMember> readMember(const Archive& archive, zip_uint64_t index,
                                             const std::string& path) {
  zip_stat_t st;
  zip_stat_init(&st);
  if (zip_stat_index(archive.get(), index, 0, &st) != 0)
    throw Error(cat("'", path, "' member ", index, ": ", archive.errorText()));
  const std::string name = (st.valid & ZIP_STAT_NAME) ? st.name : "";
  const std::string what = cat("'", path, "' member ", name);
  const std::string suffix = ".npy";
  if (name.size() <= suffix.size() ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
    throw Error(cat(what, ": not a .npy member"));
  if (!(st.valid & ZIP_STAT_SIZE)) throw Error(cat(what, ": no size in the archive"));
  Member member(archive, index, what);
  std::vector<uint8_t> piece(size_t(std::min<uint64_t>(st.size, kReadPieceBytes)));
  member.read(piece.data(), piece.size());
  const NpyHeader header = parseNpyHeader(piece.data(), piece.size(), what);
  if (header.fortranOrder) throw Error(cat(what, ": Fortran order (only C order is read)"));
  NpzMember m;
  m.descr = header.descr;
  m.shape = header.shape;
  const uint64_t bytes = arrayBytes(m.descr, m.shape, what);
  if (bytes != st.size - header.dataOffset)
    throw Error(cat(what, ": ", st.size - header.dataOffset, " data bytes, dtype '", m.descr,
                    "' and the shape make ", bytes));
  // Appended piece by piece: resize() would first write zeros over all of it (on 4.5 GB of
  // 1 MiB members, 0.4 s of the 2.6 s the read takes; bench/npz_zip64.sh).
  m.data.reserve(size_t(bytes));
  m.data.assign(piece.begin() + std::ptrdiff_t(header.dataOffset), piece.end());
  while (m.data.size() < bytes) {
    const size_t n = size_t(std::min<uint64_t>(bytes - m.data.size(), piece.size()));
    member.read(piece.data(), n);
    m.data.insert(m.data.end(), piece.begin(), piece.begin() + std::ptrdiff_t(n));
  }
  member.checkEnd();
  return {name.substr(0, name.size() - suffix.size()), std::move(m)};
}

/// Decodes one UTF-8 code point at `p`; false for a malformed, overlong or surrogate sequence.
bool nextCodePoint(const std::string& s, size_t& p, uint32_t& cp) {
  const auto byte = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char b0 = byte(p);
  size_t n;
  uint32_t min;
  if (b0 < 0x80) {
    cp = b0;
    ++p;
    return true;
  } else if ((b0 & 0xe0) == 0xc0) {
    n = 2, cp = b0 & 0x1fu, min = 0x80;
  } else if ((b0 & 0xf0) == 0xe0) {
    n = 3, cp = b0 & 0x0fu, min = 0x800;
  } else if ((b0 & 0xf8) == 0xf0) {
    n = 4, cp = b0 & 0x07u, min = 0x10000;
  } else {
    return false;
  }
  if (p + n > s.size()) return false;
  for (size_t k = 1; k < n; ++k) {
    if ((byte(p + k) & 0xc0) != 0x80) return false;
    cp = (cp << 6) | (byte(p + k) & 0x3fu);
  }
  if (cp < min || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return false;
  p += n;
  return true;
}

std::vector<uint32_t> codePointsOf(const std::string& s, const std::string& what) {
  std::vector<uint32_t> out;
  for (size_t p = 0; p < s.size();) {
    uint32_t cp = 0;
    if (!nextCodePoint(s, p, cp)) throw Error(cat(what, ": not valid UTF-8 at byte ", p));
    out.push_back(cp);
  }
  return out;
}

}  // namespace

NpzArray npzStringArray(const std::string& name, const std::vector<std::string>& strings,
                        std::vector<uint8_t>& storage) {
  std::vector<std::vector<uint32_t>> text;
  size_t width = 1;
  for (size_t k = 0; k < strings.size(); ++k) {
    text.push_back(codePointsOf(strings[k], cat("array '", name, "' string ", k)));
    width = std::max(width, text.back().size());
  }
  storage.assign(strings.size() * width * 4, 0);
  for (size_t k = 0; k < text.size(); ++k)
    for (size_t c = 0; c < text[k].size(); ++c)
      for (size_t b = 0; b < 4; ++b)
        storage[4 * (k * width + c) + b] = uint8_t((text[k][c] >> (8 * b)) & 0xffu);
  return {name, cat("<U", width), {uint64_t(strings.size())}, storage.data(), storage.size()};
}

void writeNpz(const std::string& path, const std::vector<NpzArray>& arrays) {
  std::set<std::string> names;
  for (const NpzArray& a : arrays) checkArray(a, path, names);
  std::vector<std::string> headers;
  for (const NpzArray& a : arrays) headers.push_back(npyHeader(a.descr, a.shape));
  // libzip writes no file for an archive without members; np.savez writes the end of central
  // directory record alone: its signature and 18 zero bytes.
  if (arrays.empty()) {
    const std::string empty = std::string("PK\x05\x06", 4) + std::string(18, '\0');
    writeBytesAtomically(path, empty.data(), empty.size());
    return;
  }
  writeAtomically(path, [&](const std::string& tmp) {
    Archive archive(tmp, ZIP_CREATE | ZIP_TRUNCATE, "libzip");
    for (size_t k = 0; k < arrays.size(); ++k) {
      const NpzArray& a = arrays[k];
      const std::string what = cat("array '", a.name, "'");
      // The .npy is two pieces, its header and the caller's bytes, never joined in memory.
      const zip_buffer_fragment_t pieces[2] = {
          {reinterpret_cast<zip_uint8_t*>(headers[k].data()), headers[k].size()},
          {static_cast<zip_uint8_t*>(const_cast<void*>(a.data)), a.bytes}};
      zip_source_t* source = zip_source_buffer_fragment(archive.get(), pieces, 2, 0);
      if (source == nullptr) throw Error(cat(what, ": ", archive.errorText()));
      const zip_int64_t index =
          zip_file_add(archive.get(), (a.name + ".npy").c_str(), source, ZIP_FL_ENC_UTF_8);
      if (index < 0) {
        zip_source_free(source);
        throw Error(cat(what, ": ", archive.errorText()));
      }
      if (zip_set_file_compression(archive.get(), zip_uint64_t(index), ZIP_CM_STORE, 0) != 0 ||
          zip_file_set_dostime(archive.get(), zip_uint64_t(index), kDosTimeMidnight, kDosDate1980,
                               0) != 0)
        throw Error(cat(what, ": ", archive.errorText()));
    }
    archive.close("libzip");
  });
}

std::vector<std::pair<std::string, NpzMember>> readNpz(const std::string& path) {
  const Archive archive(path, ZIP_RDONLY, cat("'", path, "'"));
  const zip_int64_t entries = zip_get_num_entries(archive.get(), 0);
  if (entries < 0) throw Error(cat("'", path, "': ", archive.errorText()));
  std::vector<std::pair<std::string, NpzMember>> members;
  for (zip_int64_t k = 0; k < entries; ++k)
    members.push_back(readMember(archive, zip_uint64_t(k), path));
  return members;
}

}  // namespace aperture
