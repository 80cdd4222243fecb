// NumPy .npz archives: a zip (PKWARE's APPNOTE.TXT) whose members "NAME.npy" are stored
// (method 0, no compression), as np.savez writes them.
//
//   per member    local file header (30 bytes + name + extra), then the .npy bytes
//   then          the central directory: one 46-byte header (+ name + extra) per member
//   then          [zip64 end of central directory record (56 bytes) and its locator (20)]
//                 end of central directory record (22 bytes, no comment)
//
// All fields little-endian. A size or offset that does not fit 32 bits is stored as
// 0xFFFFFFFF and given in full in the zip64 extended information extra field (id 0x0001):
// in a local header both sizes (uncompressed, then compressed); in a central header only the
// fields that hold 0xFFFFFFFF, in the order uncompressed size, compressed size, local header
// offset. The end record's counts and central directory size and offset likewise defer to the
// zip64 end record when they do not fit. Members are written with the CRC-32 known up front
// (no data descriptor), the DOS date 1980-01-01 00:00 (archives of the same arrays are the
// same bytes), and the UTF-8 flag (bit 11) when a name is not ASCII.
#include "core/io/npz.h"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <set>

#include "core/io/atomic_file.h"
#include "core/io/npy.h"
#include "core/util/error.h"
#include "core/util/little_endian.h"
#include "core/util/mapped_file.h"

namespace aperture {

namespace {

constexpr uint32_t kLocalHeaderSignature = 0x04034b50;
constexpr uint32_t kCentralHeaderSignature = 0x02014b50;
constexpr uint32_t kZip64EndSignature = 0x06064b50;
constexpr uint32_t kZip64LocatorSignature = 0x07064b50;
constexpr uint32_t kEndSignature = 0x06054b50;
constexpr size_t kLocalHeaderBytes = 30;
constexpr size_t kCentralHeaderBytes = 46;
constexpr size_t kZip64EndBytes = 56;
constexpr size_t kZip64LocatorBytes = 20;
constexpr size_t kEndBytes = 22;
constexpr uint16_t kZip64ExtraId = 0x0001;
/// "Version needed to extract": 2.0 for stored members, 4.5 for zip64.
constexpr uint16_t kVersionPlain = 20;
constexpr uint16_t kVersionZip64 = 45;
constexpr uint16_t kUtf8NameFlag = 1u << 11;
constexpr uint16_t kEncryptedFlag = 1u << 0;
constexpr uint16_t kDosDate1980 = (0 << 9) | (1 << 5) | 1;  // year − 1980, month, day
constexpr uint32_t kMax32 = 0xffffffffu;
constexpr uint16_t kMax16 = 0xffffu;

/// A 32-bit field: the value, or 0xFFFFFFFF when it is in the zip64 extra field instead.
uint32_t field32(uint64_t v, bool inZip64) { return inZip64 ? kMax32 : uint32_t(v); }

/// `crc` continued over `bytes` bytes at `data`. (zlib's crc32_z returns its initial value for
/// a null buffer, whatever `crc` was: an empty array must not reach it.)
uint32_t crcOf(uint32_t crc, const void* data, uint64_t bytes) {
  if (bytes == 0) return crc;
  return uint32_t(crc32_z(crc, static_cast<const Bytef*>(data), z_size_t(bytes)));
}

/// CRC-32 of no bytes.
constexpr uint32_t kCrcStart = 0;

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

bool isAscii(const std::string& s) {
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return (static_cast<unsigned char>(c) & 0x80) == 0; });
}

/// What writeNpz knows of a member once its local header is written.
struct MemberRecord {
  std::string name;  ///< "NAME.npy"
  uint32_t crc = 0;
  uint64_t size = 0;    ///< the .npy's bytes (stored: compressed = uncompressed)
  uint64_t offset = 0;  ///< of its local header
};

std::string localHeader(const MemberRecord& m, bool zip64) {
  std::string h;
  appendLittleEndian<uint32_t>(h, kLocalHeaderSignature);
  appendLittleEndian<uint16_t>(h, zip64 ? kVersionZip64 : kVersionPlain);
  appendLittleEndian<uint16_t>(h, isAscii(m.name) ? 0 : kUtf8NameFlag);
  appendLittleEndian<uint16_t>(h, 0);  // stored
  appendLittleEndian<uint16_t>(h, 0);  // time 00:00:00
  appendLittleEndian<uint16_t>(h, kDosDate1980);
  appendLittleEndian<uint32_t>(h, m.crc);
  appendLittleEndian<uint32_t>(h, field32(m.size, zip64));  // compressed
  appendLittleEndian<uint32_t>(h, field32(m.size, zip64));  // uncompressed
  appendLittleEndian<uint16_t>(h, uint16_t(m.name.size()));
  appendLittleEndian<uint16_t>(h, zip64 ? 4 + 16 : 0);
  h += m.name;
  if (zip64) {
    appendLittleEndian<uint16_t>(h, kZip64ExtraId);
    appendLittleEndian<uint16_t>(h, 16);
    appendLittleEndian<uint64_t>(h, m.size);  // uncompressed
    appendLittleEndian<uint64_t>(h, m.size);  // compressed
  }
  return h;
}

std::string centralHeader(const MemberRecord& m, bool forceZip64) {
  const bool sizes64 = forceZip64 || m.size >= kMax32;
  const bool offset64 = forceZip64 || m.offset >= kMax32;
  std::string extra;
  if (sizes64 || offset64) {
    appendLittleEndian<uint16_t>(extra, kZip64ExtraId);
    appendLittleEndian<uint16_t>(extra, uint16_t((sizes64 ? 16 : 0) + (offset64 ? 8 : 0)));
    if (sizes64) {
      appendLittleEndian<uint64_t>(extra, m.size);
      appendLittleEndian<uint64_t>(extra, m.size);
    }
    if (offset64) appendLittleEndian<uint64_t>(extra, m.offset);
  }
  const uint16_t version = extra.empty() ? kVersionPlain : kVersionZip64;
  std::string h;
  appendLittleEndian<uint32_t>(h, kCentralHeaderSignature);
  appendLittleEndian<uint16_t>(
      h, version);  // made by: MS-DOS host (no Unix permissions), this version
  appendLittleEndian<uint16_t>(h, version);  // needed to extract
  appendLittleEndian<uint16_t>(h, isAscii(m.name) ? 0 : kUtf8NameFlag);
  appendLittleEndian<uint16_t>(h, 0);  // stored
  appendLittleEndian<uint16_t>(h, 0);
  appendLittleEndian<uint16_t>(h, kDosDate1980);
  appendLittleEndian<uint32_t>(h, m.crc);
  appendLittleEndian<uint32_t>(h, field32(m.size, sizes64));
  appendLittleEndian<uint32_t>(h, field32(m.size, sizes64));
  appendLittleEndian<uint16_t>(h, uint16_t(m.name.size()));
  appendLittleEndian<uint16_t>(h, uint16_t(extra.size()));
  appendLittleEndian<uint16_t>(h, 0);  // comment length
  appendLittleEndian<uint16_t>(h, 0);  // disk number start
  appendLittleEndian<uint16_t>(h, 0);  // internal attributes
  appendLittleEndian<uint32_t>(h, 0);  // external attributes
  appendLittleEndian<uint32_t>(h, field32(m.offset, offset64));
  return h + m.name + extra;
}

/// The zip64 end record and locator (when needed) and the end record, for a central directory
/// of `entries` members, `size` bytes at `offset`.
std::string endRecords(uint64_t entries, uint64_t size, uint64_t offset, bool forceZip64) {
  const bool zip64 = forceZip64 || entries >= kMax16 || size >= kMax32 || offset >= kMax32;
  std::string out;
  if (zip64) {
    const uint64_t zip64EndOffset = offset + size;
    appendLittleEndian<uint32_t>(out, kZip64EndSignature);
    appendLittleEndian<uint64_t>(out, kZip64EndBytes - 12);  // the record's size after this field
    appendLittleEndian<uint16_t>(out, kVersionZip64);
    appendLittleEndian<uint16_t>(out, kVersionZip64);
    appendLittleEndian<uint32_t>(out, 0);  // this disk
    appendLittleEndian<uint32_t>(out, 0);  // the disk of the central directory
    appendLittleEndian<uint64_t>(out, entries);
    appendLittleEndian<uint64_t>(out, entries);
    appendLittleEndian<uint64_t>(out, size);
    appendLittleEndian<uint64_t>(out, offset);
    appendLittleEndian<uint32_t>(out, kZip64LocatorSignature);
    appendLittleEndian<uint32_t>(out, 0);  // the disk of the zip64 end record
    appendLittleEndian<uint64_t>(out, zip64EndOffset);
    appendLittleEndian<uint32_t>(out, 1);  // disks in all
  }
  const uint16_t entries16 = zip64 ? kMax16 : uint16_t(entries);
  appendLittleEndian<uint32_t>(out, kEndSignature);
  appendLittleEndian<uint16_t>(out, 0);
  appendLittleEndian<uint16_t>(out, 0);
  appendLittleEndian<uint16_t>(out, entries16);
  appendLittleEndian<uint16_t>(out, entries16);
  appendLittleEndian<uint32_t>(out, field32(size, zip64));
  appendLittleEndian<uint32_t>(out, field32(offset, zip64));
  appendLittleEndian<uint16_t>(out, 0);  // comment length
  return out;
}

void checkArray(const NpzArray& a, const std::string& path, std::set<std::string>& names) {
  if (a.name.empty()) throw Error(cat("cannot write '", path, "': an array has an empty name"));
  if (a.name.find('\0') != std::string::npos || a.name.size() > kMax16 - 4)
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

// ---- reading ----

/// Little-endian fields of a mapped archive, each read checked against its end.
class ZipBytes {
 public:
  ZipBytes(const std::string& path, const uint8_t* data, size_t size)
      : path_(path), data_(data), size_(size) {}

  size_t size() const { return size_; }
  const uint8_t* at(uint64_t offset) const { return data_ + offset; }

  uint64_t read(uint64_t offset, size_t bytes, const std::string& what) const {
    need(offset, bytes, what);
    return loadLittleEndianBytes(data_ + offset, bytes);
  }

  void need(uint64_t offset, uint64_t bytes, const std::string& what) const {
    if (offset > size_ || bytes > size_ - offset)
      throw Error(cat("'", path_, "': truncated zip: ", what, " needs ", bytes, " bytes at offset ",
                      offset, ", the file has ", size_));
  }

 private:
  const std::string& path_;
  const uint8_t* data_;
  size_t size_;
};

struct CentralDirectory {
  uint64_t entries = 0;
  uint64_t size = 0;
  uint64_t offset = 0;
};

CentralDirectory findCentralDirectory(const ZipBytes& z, const std::string& path) {
  if (z.size() < kEndBytes) throw Error(cat("'", path, "': not a zip archive (too short)"));
  // The end record is the last 22 bytes plus a comment of at most 65535 bytes.
  uint64_t end = z.size() - kEndBytes;
  const uint64_t lowest = end > kMax16 ? end - kMax16 : 0;
  while (!(z.read(end, 4, "the end record") == kEndSignature &&
           end + kEndBytes + z.read(end + 20, 2, "the comment length") == z.size())) {
    if (end == lowest)
      throw Error(cat("'", path, "': not a zip archive (no end of central directory record)"));
    --end;
  }
  CentralDirectory cd;
  cd.entries = z.read(end + 10, 2, "the end record");
  cd.size = z.read(end + 12, 4, "the end record");
  cd.offset = z.read(end + 16, 4, "the end record");
  if (end >= kZip64LocatorBytes &&
      z.read(end - kZip64LocatorBytes, 4, "the zip64 locator") == kZip64LocatorSignature) {
    const uint64_t record = z.read(end - kZip64LocatorBytes + 8, 8, "the zip64 locator");
    if (z.read(record, 4, "the zip64 end record") != kZip64EndSignature)
      throw Error(cat("'", path, "': the zip64 locator points to offset ", record,
                      ", which holds no zip64 end record"));
    cd.entries = z.read(record + 32, 8, "the zip64 end record");
    cd.size = z.read(record + 40, 8, "the zip64 end record");
    cd.offset = z.read(record + 48, 8, "the zip64 end record");
  }
  z.need(cd.offset, cd.size, "the central directory");
  return cd;
}

/// One central directory entry: where its data is and what it claims.
struct Entry {
  std::string name;
  uint16_t flags = 0;
  uint16_t method = 0;
  uint32_t crc = 0;
  uint64_t compressed = 0;
  uint64_t uncompressed = 0;
  uint64_t offset = 0;
  size_t headerBytes = 0;  ///< of the central header, name, extra and comment
};

/// The zip64 extra field's values replace the fields that hold 0xFFFFFFFF, in order.
void applyZip64Extra(const ZipBytes& z, uint64_t extra, uint64_t extraBytes, Entry& e,
                     const std::string& what) {
  uint64_t p = extra;
  while (p + 4 <= extra + extraBytes) {
    const uint64_t id = z.read(p, 2, what), bytes = z.read(p + 2, 2, what);
    if (p + 4 + bytes > extra + extraBytes)
      throw Error(cat(what, ": an extra field runs past its header"));
    if (id == kZip64ExtraId) {
      uint64_t q = p + 4;
      for (uint64_t* field : {&e.uncompressed, &e.compressed, &e.offset}) {
        if (*field != kMax32) continue;
        if (q + 8 > p + 4 + bytes) throw Error(cat(what, ": zip64 extra field too short"));
        *field = z.read(q, 8, what);
        q += 8;
      }
    }
    p += 4 + bytes;
  }
}

Entry readEntry(const ZipBytes& z, uint64_t p, const std::string& path) {
  const std::string what = cat("'", path, "' central directory entry at offset ", p);
  if (z.read(p, 4, what) != kCentralHeaderSignature)
    throw Error(cat(what, ": no central header signature"));
  Entry e;
  e.flags = uint16_t(z.read(p + 8, 2, what));
  e.method = uint16_t(z.read(p + 10, 2, what));
  e.crc = uint32_t(z.read(p + 16, 4, what));
  e.compressed = z.read(p + 20, 4, what);
  e.uncompressed = z.read(p + 24, 4, what);
  const uint64_t nameBytes = z.read(p + 28, 2, what);
  const uint64_t extraBytes = z.read(p + 30, 2, what);
  const uint64_t commentBytes = z.read(p + 32, 2, what);
  e.offset = z.read(p + 42, 4, what);
  z.need(p + kCentralHeaderBytes, nameBytes + extraBytes + commentBytes, what);
  e.name.assign(reinterpret_cast<const char*>(z.at(p + kCentralHeaderBytes)), size_t(nameBytes));
  applyZip64Extra(z, p + kCentralHeaderBytes + nameBytes, extraBytes, e,
                  cat("'", path, "' member ", e.name));
  e.headerBytes = size_t(kCentralHeaderBytes + nameBytes + extraBytes + commentBytes);
  return e;
}

std::pair<std::string, NpzMember> readMember(const ZipBytes& z, const Entry& e,
                                             const std::string& path) {
  const std::string what = cat("'", path, "' member ", e.name);
  if (e.flags & kEncryptedFlag) throw Error(cat(what, ": encrypted members are not read"));
  if (e.method != 0)
    throw Error(cat(what, ": compression method ", e.method,
                    " (only stored members are read: np.savez, not np.savez_compressed)"));
  if (e.compressed != e.uncompressed)
    throw Error(cat(what, ": stored member with compressed size ", e.compressed,
                    " and uncompressed size ", e.uncompressed));
  const std::string suffix = ".npy";
  if (e.name.size() <= suffix.size() ||
      e.name.compare(e.name.size() - suffix.size(), suffix.size(), suffix) != 0)
    throw Error(cat(what, ": not a .npy member"));
  if (z.read(e.offset, 4, what) != kLocalHeaderSignature)
    throw Error(cat(what, ": no local header at offset ", e.offset));
  const uint64_t data = e.offset + kLocalHeaderBytes + z.read(e.offset + 26, 2, what) +
                        z.read(e.offset + 28, 2, what);
  z.need(data, e.compressed, cat(what, "'s data"));
  const uint32_t crc = crcOf(kCrcStart, z.at(data), e.compressed);
  if (crc != e.crc)
    throw Error(cat(what, ": CRC-32 of the data is ", crc, ", the archive says ", e.crc));
  const NpyHeader header = parseNpyHeader(z.at(data), size_t(e.compressed), what);
  if (header.fortranOrder) throw Error(cat(what, ": Fortran order (only C order is read)"));
  NpzMember m;
  m.descr = header.descr;
  m.shape = header.shape;
  const uint64_t bytes = arrayBytes(m.descr, m.shape, what);
  if (bytes != e.compressed - header.dataOffset)
    throw Error(cat(what, ": ", e.compressed - header.dataOffset, " data bytes, dtype '", m.descr,
                    "' and the shape make ", bytes));
  m.data.assign(z.at(data + header.dataOffset), z.at(data + e.compressed));
  return {e.name.substr(0, e.name.size() - suffix.size()), std::move(m)};
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

void writeNpz(const std::string& path, const std::vector<NpzArray>& arrays,
              const NpzOptions& options) {
  std::set<std::string> names;
  for (const NpzArray& a : arrays) checkArray(a, path, names);
  // The pieces point into `headers`: reserved up front, so no push_back moves a string.
  std::vector<std::string> headers;
  headers.reserve(2 * arrays.size() + 2);
  std::vector<BytePiece> pieces;
  std::vector<MemberRecord> members;
  uint64_t offset = 0;
  for (const NpzArray& a : arrays) {
    headers.push_back(npyHeader(a.descr, a.shape));
    const std::string& npy = headers.back();
    MemberRecord m;
    m.name = a.name + ".npy";
    m.size = npy.size() + a.bytes;
    m.crc = crcOf(crcOf(kCrcStart, npy.data(), npy.size()), a.data, a.bytes);
    m.offset = offset;
    headers.push_back(localHeader(m, options.forceZip64 || m.size >= kMax32));
    pieces.push_back({headers.back().data(), headers.back().size()});
    pieces.push_back({npy.data(), npy.size()});
    pieces.push_back({a.data, size_t(a.bytes)});
    offset += headers.back().size() + m.size;
    members.push_back(std::move(m));
  }
  std::string central;
  for (const MemberRecord& m : members) central += centralHeader(m, options.forceZip64);
  const uint64_t centralBytes = central.size();
  central += endRecords(members.size(), centralBytes, offset, options.forceZip64);
  headers.push_back(std::move(central));
  pieces.push_back({headers.back().data(), headers.back().size()});
  writePiecesAtomically(path, pieces);
}

std::vector<std::pair<std::string, NpzMember>> readNpz(const std::string& path) {
  const MappedFile file(path);
  const ZipBytes z(path, reinterpret_cast<const uint8_t*>(file.data()), file.size());
  const CentralDirectory cd = findCentralDirectory(z, path);
  std::vector<std::pair<std::string, NpzMember>> members;
  uint64_t p = cd.offset;
  for (uint64_t k = 0; k < cd.entries; ++k) {
    if (p >= cd.offset + cd.size)
      throw Error(cat("'", path, "': the central directory ends after ", k, " of its ", cd.entries,
                      " entries"));
    const Entry e = readEntry(z, p, path);
    members.push_back(readMember(z, e, path));
    p += e.headerBytes;
  }
  return members;
}

}  // namespace aperture
