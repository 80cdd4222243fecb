// .npy headers (core/io/npy.h) and .npz archives (core/io/npz.h). The archive's bytes are parsed
// here independently of core/io/npz.cpp from the zip format (PKWARE's APPNOTE): signatures,
// sizes, offsets, the zip64 fields, and a CRC-32 computed bit by bit (the reflected
// polynomial 0xEDB88320, no table, no zlib). When a Python with NumPy is found (the project's
// .venv, or APERTURE_TEST_PYTHON), np.load reads the archives too, and readNpz reads what
// np.savez writes, zip64 records included, and refuses np.savez_compressed's by name.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/npy.h"
#include "core/io/npz.h"
#include "core/util/error.h"
#include "tests/support.h"

namespace aperture {
namespace {

namespace fs = std::filesystem;
using test::errorOf;

uint32_t referenceCrc32(const std::string& bytes) {
  uint32_t crc = 0xffffffffu;
  for (unsigned char byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ ((crc & 1u) ? 0xedb88320u : 0u);
  }
  return ~crc;
}

uint64_t le(const std::string& s, size_t at, size_t bytes) {
  EXPECT_LE(at + bytes, s.size());
  if (at + bytes > s.size()) return 0;
  uint64_t v = 0;
  for (size_t k = 0; k < bytes; ++k)
    v |= uint64_t(static_cast<unsigned char>(s[at + k])) << (8 * k);
  return v;
}

template <typename T>
std::string bytesOf(const std::vector<T>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

bool hasNonAscii(const std::string& s) {
  for (unsigned char c : s)
    if (c >= 0x80) return true;
  return false;
}

/// One member as the test's own parser sees it, from its local header and central entry.
struct ParsedMember {
  std::string name;
  uint64_t localOffset = 0;
  uint32_t crc = 0;
  uint64_t size = 0;
  std::string data;  ///< the stored .npy bytes
  bool localZip64 = false;
  bool centralZip64 = false;
};

struct ParsedArchive {
  std::vector<ParsedMember> members;
  bool zip64End = false;
  uint64_t entries = 0;  ///< as the end records give it
};

/// Reads a zip64 extra field (id 1) of `extra` into the fields that hold 0xFFFFFFFF.
bool readZip64Extra(const std::string& extra, std::vector<uint64_t*> fields) {
  size_t p = 0;
  while (p + 4 <= extra.size()) {
    const uint64_t id = le(extra, p, 2), n = le(extra, p + 2, 2);
    if (id == 1) {
      size_t q = p + 4;
      for (uint64_t* f : fields)
        if (*f == 0xffffffffu) {
          EXPECT_LE(q + 8, p + 4 + n);
          *f = le(extra, q, 8);
          q += 8;
        }
      EXPECT_EQ(q, p + 4 + n) << "zip64 extra field of unexpected length";
      return true;
    }
    p += 4 + n;
  }
  return false;
}

/// Walks the archive from both ends: local headers in order from offset 0, and the central
/// directory from the end record (and the zip64 records when present). Checks that both agree
/// and that the pieces tile the file exactly.
ParsedArchive parseArchive(const std::string& zip) {
  ParsedArchive out;
  // End of central directory record: the last 22 bytes (no comment).
  const size_t end = zip.size() - 22;
  EXPECT_EQ(le(zip, end, 4), 0x06054b50u);
  EXPECT_EQ(le(zip, end + 20, 2), 0u) << "comment length";
  uint64_t entries = le(zip, end + 10, 2), cdSize = le(zip, end + 12, 4),
           cdOffset = le(zip, end + 16, 4);
  EXPECT_EQ(le(zip, end + 8, 2), entries);
  size_t cdEnd = end;
  if (end >= 20 && le(zip, end - 20, 4) == 0x07064b50u) {
    out.zip64End = true;
    const uint64_t record = le(zip, end - 20 + 8, 8);
    EXPECT_EQ(le(zip, end - 20 + 16, 4), 1u) << "total disks";
    EXPECT_EQ(record, end - 20 - 56);
    EXPECT_EQ(le(zip, record, 4), 0x06064b50u);
    EXPECT_EQ(le(zip, record + 4, 8), 44u) << "zip64 end record size";
    // A 16- or 32-bit field of the end record holds its value or, where that does not fit,
    // the marker 0xFFFF(FFFF); the zip64 end record holds them all.
    const uint64_t entries64 = le(zip, record + 32, 8), cdSize64 = le(zip, record + 40, 8),
                   cdOffset64 = le(zip, record + 48, 8);
    EXPECT_EQ(le(zip, record + 24, 8), entries64);
    EXPECT_TRUE(entries == entries64 || entries == 0xffffu) << entries;
    EXPECT_TRUE(cdSize == cdSize64 || cdSize == 0xffffffffu) << cdSize;
    EXPECT_TRUE(cdOffset == cdOffset64 || cdOffset == 0xffffffffu) << cdOffset;
    entries = entries64;
    cdSize = cdSize64;
    cdOffset = cdOffset64;
    cdEnd = size_t(record);
  }
  EXPECT_EQ(cdOffset + cdSize, cdEnd) << "the central directory ends where the end records start";
  out.entries = entries;

  size_t local = 0, central = size_t(cdOffset);
  for (uint64_t k = 0; k < entries; ++k) {
    ParsedMember m;
    // Central header.
    EXPECT_EQ(le(zip, central, 4), 0x02014b50u);
    const uint64_t flags = le(zip, central + 8, 2);
    EXPECT_EQ(le(zip, central + 10, 2), 0u) << "stored";
    const uint64_t timeAndDate = le(zip, central + 12, 4);
    EXPECT_EQ(timeAndDate & 0xffffu, 0u) << "DOS time 00:00:00";
    EXPECT_EQ(timeAndDate >> 16, (1u << 5) | 1u) << "DOS date 1980-01-01";
    m.crc = uint32_t(le(zip, central + 16, 4));
    uint64_t compressed = le(zip, central + 20, 4), size = le(zip, central + 24, 4);
    const size_t nameLen = le(zip, central + 28, 2), extraLen = le(zip, central + 30, 2),
                 commentLen = le(zip, central + 32, 2);
    m.localOffset = le(zip, central + 42, 4);
    m.name = zip.substr(central + 46, nameLen);
    EXPECT_EQ(bool(flags & 0x800), hasNonAscii(m.name)) << "UTF-8 flag of " << m.name;
    m.centralZip64 = readZip64Extra(zip.substr(central + 46 + nameLen, extraLen),
                                    {&size, &compressed, &m.localOffset});
    EXPECT_EQ(le(zip, central + 6, 2), m.centralZip64 ? 45u : 20u) << "version needed";
    EXPECT_EQ(compressed, size);
    m.size = size;
    central += 46 + nameLen + extraLen + commentLen;

    // Its local header, which must come next in the file.
    EXPECT_EQ(m.localOffset, local) << m.name;
    EXPECT_EQ(le(zip, local, 4), 0x04034b50u);
    EXPECT_EQ(le(zip, local + 6, 2), flags);
    EXPECT_EQ(le(zip, local + 8, 2), 0u);
    EXPECT_EQ(le(zip, local + 10, 4), timeAndDate);
    EXPECT_EQ(le(zip, local + 14, 4), m.crc);
    uint64_t localCompressed = le(zip, local + 18, 4), localSize = le(zip, local + 22, 4);
    const size_t localName = le(zip, local + 26, 2), localExtra = le(zip, local + 28, 2);
    EXPECT_EQ(zip.substr(local + 30, localName), m.name);
    m.localZip64 = readZip64Extra(zip.substr(local + 30 + localName, localExtra),
                                  {&localSize, &localCompressed});
    EXPECT_EQ(le(zip, local + 4, 2), m.localZip64 ? 45u : 20u);
    EXPECT_EQ(localSize, m.size);
    EXPECT_EQ(localCompressed, m.size);
    const size_t data = local + 30 + localName + localExtra;
    m.data = zip.substr(data, size_t(m.size));
    EXPECT_EQ(referenceCrc32(m.data), m.crc) << m.name;
    local = data + size_t(m.size);
    out.members.push_back(m);
  }
  EXPECT_EQ(local, cdOffset) << "the members end where the central directory starts";
  EXPECT_EQ(central, cdOffset + cdSize);
  return out;
}

/// The arrays of the tests: uint32 (3,), float64 (2, 2), int32 (0,), and strings.
struct Fixture {
  std::vector<uint32_t> counts = {7, 0, 4000000000u};
  std::vector<double> matrix = {1.5, -2.25, 1e300, -0.0};
  std::vector<int32_t> none;
  std::vector<uint8_t> nameStorage;
  std::vector<NpzArray> arrays;

  Fixture() {
    arrays = {{"face_view_count", "<u4", {3}, counts.data(), 12},
              {"matrix", "<f8", {2, 2}, matrix.data(), 32},
              {"empty", "<i4", {0}, none.data(), 0},
              npzStringArray("camera_names", {"cam0", "\xce\xa9mega/1.png"}, nameStorage)};
  }
};

std::string dictOf(const std::string& npy) {
  const size_t len = size_t(le(npy, 8, 2));
  return npy.substr(10, len);
}

TEST(NpzNpyHeader, LayoutAndParseBack) {
  for (const auto& [descr, shape, shapeText] :
       {std::tuple<std::string, std::vector<uint64_t>, std::string>{
            "<f4", {480, 640}, "(480, 640)"},
        {"<u8", {5}, "(5,)"},
        {"<U12", {}, "()"},
        {"<i4", {2, 3, 4}, "(2, 3, 4)"}}) {
    const std::string h = npyHeader(descr, shape);
    EXPECT_EQ(h.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
    EXPECT_EQ(h.size() % 64, 0u) << "data aligned to 64 bytes";
    EXPECT_EQ(le(h, 8, 2), h.size() - 10);
    EXPECT_EQ(h.back(), '\n');
    const std::string dict = dictOf(h);
    const std::string expected =
        "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shapeText + ", }";
    EXPECT_EQ(dict.substr(0, expected.size()), expected);
    EXPECT_EQ(dict.find_first_not_of(' ', expected.size()), dict.size() - 1);
    const NpyHeader back =
        parseNpyHeader(reinterpret_cast<const uint8_t*>(h.data()), h.size(), "x");
    EXPECT_EQ(back.descr, descr);
    EXPECT_EQ(back.shape, shape);
    EXPECT_FALSE(back.fortranOrder);
    EXPECT_EQ(back.dataOffset, h.size());
  }
}

TEST(NpzNpyHeader, ReadsVersion2KeysInAnyOrder) {
  const std::string dict = "{\"shape\": (3,2), \"fortran_order\": True, \"descr\": \"<f8\"}\n";
  std::string h("\x93NUMPY\x02\x00", 8);
  for (int k = 0; k < 4; ++k) h.push_back(char((dict.size() >> (8 * k)) & 0xff));
  h += dict;
  const NpyHeader back = parseNpyHeader(reinterpret_cast<const uint8_t*>(h.data()), h.size(), "v2");
  EXPECT_EQ(back.descr, "<f8");
  EXPECT_EQ(back.shape, (std::vector<uint64_t>{3, 2}));
  EXPECT_TRUE(back.fortranOrder);
  EXPECT_EQ(back.dataOffset, 12 + dict.size());
}

TEST(NpzNpyHeader, MalformedHeadersNameTheSource) {
  const auto header = [](const std::string& dict) {
    std::string h("\x93NUMPY\x01\x00", 8);
    h.push_back(char(dict.size() & 0xff));
    h.push_back(char(dict.size() >> 8));
    return h + dict;
  };
  for (const std::string& bytes :
       {std::string("\x93NUMPX\x01\x00\x00\x00", 10), header("{'descr': '<f4', 'shape': (1,)}"),
        header("{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (1,)}"),
        header("{'descr': '<f4', 'fortran_order': False, 'shape': (1, -2)}"),
        header("{'descr': '<f4', 'fortran_order': False, 'shape': (1,), 'x': 1}"),
        header("{'descr': '<f4', 'fortran_order': False, 'shape': (1,)").substr(0, 30)}) {
    const std::string message = errorOf([&] {
      parseNpyHeader(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), "in.npy");
    });
    EXPECT_NE(message.find("in.npy"), std::string::npos) << message;
  }
  EXPECT_EQ(npyItemBytes("<U12", "x"), 48u);
  EXPECT_EQ(npyItemBytes("|u1", "x"), 1u);
  EXPECT_EQ(npyItemBytes("<f8", "x"), 8u);
  EXPECT_NE(errorOf([] { npyItemBytes(">f4", "file.npz"); }).find("file.npz"), std::string::npos);
  EXPECT_NE(errorOf([] { npyItemBytes("<f3", "x"); }), "");
}

TEST(NpzStrings, Utf32LittleEndianPaddedToTheLongest) {
  std::vector<uint8_t> storage;
  // "Ωmega/1.png": U+03A9 then 10 ASCII characters: 11 code points, 12 bytes of UTF-8.
  const NpzArray a = npzStringArray("names", {"cam0", "\xce\xa9mega/1.png"}, storage);
  EXPECT_EQ(a.descr, "<U11");
  EXPECT_EQ(a.shape, (std::vector<uint64_t>{2}));
  ASSERT_EQ(a.bytes, 2u * 11 * 4);
  std::vector<uint8_t> expected(2 * 11 * 4, 0);
  const char* ascii = "cam0";
  for (int k = 0; k < 4; ++k) expected[size_t(4 * k)] = uint8_t(ascii[k]);
  expected[44] = 0xa9;
  expected[45] = 0x03;
  const char* rest = "mega/1.png";
  for (int k = 0; k < 10; ++k) expected[size_t(44 + 4 * (k + 1))] = uint8_t(rest[k]);
  EXPECT_EQ(std::memcmp(a.data, expected.data(), expected.size()), 0);

  const NpzArray empty = npzStringArray("none", {}, storage);
  EXPECT_EQ(empty.descr, "<U1");
  EXPECT_EQ(empty.bytes, 0u);
  for (const char* bad : {"\xff", "a\xc3", "\xc0\xaf", "\xed\xa0\x80"})
    EXPECT_NE(errorOf([&] {
                npzStringArray("names", {"ok", bad}, storage);
              }).find("names"),
              std::string::npos)
        << bad;
}

void expectMembersMatch(const ParsedArchive& zip, const Fixture& f) {
  ASSERT_EQ(zip.members.size(), f.arrays.size());
  for (size_t k = 0; k < f.arrays.size(); ++k) {
    const NpzArray& a = f.arrays[k];
    const ParsedMember& m = zip.members[k];
    EXPECT_EQ(m.name, a.name + ".npy");
    const NpyHeader h =
        parseNpyHeader(reinterpret_cast<const uint8_t*>(m.data.data()), m.data.size(), m.name);
    EXPECT_EQ(h.descr, a.descr);
    EXPECT_EQ(h.shape, a.shape);
    EXPECT_EQ(m.data.substr(h.dataOffset),
              std::string(static_cast<const char*>(a.data), size_t(a.bytes)));
  }
}

void expectRoundTrip(const std::string& path, const Fixture& f) {
  const auto back = readNpz(path);
  ASSERT_EQ(back.size(), f.arrays.size());
  for (size_t k = 0; k < f.arrays.size(); ++k) {
    const NpzArray& a = f.arrays[k];
    EXPECT_EQ(back[k].first, a.name);
    EXPECT_EQ(back[k].second.descr, a.descr);
    EXPECT_EQ(back[k].second.shape, a.shape);
    EXPECT_EQ(bytesOf(back[k].second.data),
              std::string(static_cast<const char*>(a.data), size_t(a.bytes)));
  }
}

TEST(NpzArchive, BytesParsedIndependently) {
  const Fixture f;
  const std::string path = test::scratchDir() + "/v.npz";
  writeNpz(path, f.arrays);
  const ParsedArchive zip = parseArchive(test::readFile(path));
  EXPECT_FALSE(zip.zip64End);
  for (const ParsedMember& m : zip.members) {
    EXPECT_FALSE(m.localZip64);
    EXPECT_FALSE(m.centralZip64);
  }
  expectMembersMatch(zip, f);
  expectRoundTrip(path, f);
}

TEST(NpzArchive, Zip64Forced) {
  const Fixture f;
  const std::string path = test::scratchDir() + "/v64.npz";
  writeNpz(path, f.arrays, NpzOptions{true});
  const std::string bytes = test::readFile(path);
  const ParsedArchive zip = parseArchive(bytes);
  EXPECT_TRUE(zip.zip64End);
  for (const ParsedMember& m : zip.members) {
    EXPECT_TRUE(m.localZip64) << m.name;
    EXPECT_TRUE(m.centralZip64) << m.name;
  }
  // The 32-bit fields hold the 0xFFFFFFFF marker: the first local header's sizes.
  EXPECT_EQ(le(bytes, 18, 4), 0xffffffffu);
  EXPECT_EQ(le(bytes, 22, 4), 0xffffffffu);
  expectMembersMatch(zip, f);
  expectRoundTrip(path, f);
}

/// 65536 one-element uint32 arrays "a00000", ... holding their index: one member more than the
/// end record's 16-bit count holds, so the archive needs the zip64 end record and its locator
/// without being forced to.
struct ManyMembers {
  static constexpr uint32_t kCount = 65536;
  std::vector<uint32_t> values;
  std::vector<NpzArray> arrays;

  ManyMembers() : values(kCount) {
    char name[16];
    for (uint32_t k = 0; k < kCount; ++k) {
      values[k] = k;
      std::snprintf(name, sizeof name, "a%05u", k);
      arrays.push_back({name, "<u4", {1}, &values[k], 4});
    }
  }
};

TEST(NpzArchive, Zip64EndRecordPastTheMemberCount) {
  const ManyMembers many;
  const std::string path = test::scratchDir() + "/many.npz";
  writeNpz(path, many.arrays);
  const std::string bytes = test::readFile(path);
  const ParsedArchive zip = parseArchive(bytes);
  EXPECT_TRUE(zip.zip64End);
  EXPECT_EQ(zip.entries, uint64_t(ManyMembers::kCount));
  EXPECT_EQ(le(bytes, bytes.size() - 22 + 10, 2), 0xffffu) << "the end record's count: the marker";
  ASSERT_EQ(zip.members.size(), size_t(ManyMembers::kCount));
  for (uint32_t k : {0u, 1u, 65534u, 65535u}) {
    EXPECT_EQ(zip.members[k].name, many.arrays[k].name + ".npy");
    EXPECT_EQ(le(zip.members[k].data, zip.members[k].data.size() - 4, 4), k);
  }
  const auto back = readNpz(path);
  ASSERT_EQ(back.size(), size_t(ManyMembers::kCount));
  for (uint32_t k = 0; k < ManyMembers::kCount; ++k) {
    ASSERT_EQ(back[k].first, many.arrays[k].name);
    ASSERT_EQ(back[k].second.data.size(), 4u);
    uint32_t v = 0;
    std::memcpy(&v, back[k].second.data.data(), 4);
    ASSERT_EQ(v, k);
  }
}

TEST(NpzArchive, NoArraysIsTheEndRecordAlone) {
  const std::string path = test::scratchDir() + "/none.npz";
  writeNpz(path, {});
  EXPECT_EQ(test::readFile(path), std::string("PK\x05\x06", 4) + std::string(18, '\0'));
  EXPECT_TRUE(readNpz(path).empty());
}

TEST(NpzArchive, SameArraysSameBytes) {
  const Fixture f;
  const std::string dir = test::scratchDir();
  writeNpz(dir + "/a.npz", f.arrays);
  writeNpz(dir + "/b.npz", f.arrays);
  EXPECT_EQ(test::readFile(dir + "/a.npz"), test::readFile(dir + "/b.npz"));
}

/// True when `dir` holds no file at all (no result, no temporary left behind).
bool emptyDir(const std::string& dir) { return fs::is_empty(dir); }

TEST(NpzArchive, RefusalsLeaveNoFile) {
  const Fixture f;
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/bad.npz";
  std::vector<NpzArray> twice = f.arrays;
  twice.push_back(f.arrays[1]);
  std::string message = errorOf([&] { writeNpz(path, twice); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("'matrix'"), std::string::npos) << message;
  EXPECT_TRUE(emptyDir(dir));

  std::vector<NpzArray> wrongBytes = f.arrays;
  wrongBytes[0].bytes = 8;
  message = errorOf([&] { writeNpz(path, wrongBytes); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("face_view_count"), std::string::npos) << message;
  EXPECT_NE(message.find("12"), std::string::npos) << "the expected byte count: " << message;
  EXPECT_TRUE(emptyDir(dir));

  std::vector<NpzArray> unnamed = f.arrays;
  unnamed[2].name = "";
  EXPECT_NE(errorOf([&] { writeNpz(path, unnamed); }).find(path), std::string::npos);
  std::vector<NpzArray> badType = f.arrays;
  badType[0].descr = "<c8";
  EXPECT_NE(errorOf([&] { writeNpz(path, badType); }).find(path), std::string::npos);
  EXPECT_TRUE(emptyDir(dir));
}

TEST(NpzArchive, ReadRefusesCorruptMembers) {
  const Fixture f;
  const std::string dir = test::scratchDir();
  writeNpz(dir + "/ok.npz", f.arrays);
  const std::string good = test::readFile(dir + "/ok.npz");
  const ParsedArchive zip = parseArchive(good);

  // A flipped data byte in the first member: the CRC no longer matches.
  std::string corrupt = good;
  const size_t firstData = 30 + zip.members[0].name.size();
  corrupt[firstData + zip.members[0].data.size() - 1] ^= 0x01;
  test::writeFile(dir + "/crc.npz", corrupt);
  std::string message = errorOf([&] { readNpz(dir + "/crc.npz"); });
  EXPECT_NE(message.find(dir + "/crc.npz"), std::string::npos) << message;
  EXPECT_NE(message.find("face_view_count.npy"), std::string::npos) << message;
  EXPECT_NE(message.find("CRC"), std::string::npos) << message;

  // The first central header says deflate (method 8), the second one an unknown method.
  std::string deflated = good;
  const size_t central = size_t(le(good, good.size() - 22 + 16, 4));
  deflated[central + 10] = 8;
  test::writeFile(dir + "/deflate.npz", deflated);
  message = errorOf([&] { readNpz(dir + "/deflate.npz"); });
  EXPECT_NE(message.find(dir + "/deflate.npz"), std::string::npos) << message;
  EXPECT_NE(message.find("face_view_count.npy"), std::string::npos) << message;
  EXPECT_NE(message.find("compression method 8"), std::string::npos) << message;
  std::string unknown = good;
  const size_t second = central + 46 + zip.members[0].name.size();
  ASSERT_EQ(le(good, second, 4), 0x02014b50u);
  unknown[second + 10] = 77;
  test::writeFile(dir + "/unknown.npz", unknown);
  message = errorOf([&] { readNpz(dir + "/unknown.npz"); });
  EXPECT_NE(message.find(dir + "/unknown.npz"), std::string::npos) << message;
  EXPECT_NE(message.find("matrix.npy"), std::string::npos) << message;
  EXPECT_NE(message.find("compression method 77"), std::string::npos) << message;

  test::writeFile(dir + "/short.npz", good.substr(0, good.size() - 30));
  EXPECT_NE(errorOf([&] { readNpz(dir + "/short.npz"); }).find(dir + "/short.npz"),
            std::string::npos);
}

/// The project's .venv Python (scripts/venv.sh), or APERTURE_TEST_PYTHON; "" when neither has
/// NumPy.
std::string numpyPython() {
  const char* given = std::getenv("APERTURE_TEST_PYTHON");
  const std::string python =
      given && *given ? given : std::string(APERTURE_TESTS_DIR) + "/../.venv/bin/python";
  if (!fs::exists(python)) return "";
  return test::runCommand(test::quote(python) + " -c 'import numpy'") == 0 ? python : "";
}

/// Runs `script` (written to the scratch directory) with `args`; its exit code, output in `out`.
int runPython(const std::string& python, const std::string& dir, const std::string& script,
              const std::vector<std::string>& args, std::string* out) {
  test::writeFile(dir + "/check.py", script);
  std::string command = test::quote(python) + " " + test::quote(dir + "/check.py");
  for (const std::string& a : args) command += " " + test::quote(a);
  return test::runCommand(command, out);
}

TEST(NpzNumpy, NpLoadReadsEveryArray) {
  const std::string python = numpyPython();
  if (python.empty())
    GTEST_SKIP() << "no Python with NumPy (.venv beside the project or APERTURE_TEST_PYTHON); "
                    "the byte-level tests above check the layout alone";
  const Fixture f;
  const ManyMembers many;
  const std::string dir = test::scratchDir();
  writeNpz(dir + "/plain.npz", f.arrays);
  writeNpz(dir + "/zip64.npz", f.arrays, NpzOptions{true});
  writeNpz(dir + "/many.npz", many.arrays);
  // The expected values are written into the script from the test's own arrays.
  std::string output;
  const int code = runPython(
      python, dir,
      "import sys, zipfile, numpy as np\n"
      "for path in sys.argv[1:3]:\n"
      "    d = np.load(path)\n"
      "    assert list(d.keys()) == ['face_view_count', 'matrix', 'empty', 'camera_names'], "
      "list(d.keys())\n"
      "    a = d['face_view_count']\n"
      "    assert a.dtype == np.uint32 and a.tolist() == [7, 0, 4000000000], a\n"
      "    m = d['matrix']\n"
      "    assert m.dtype == np.float64 and m.shape == (2, 2)\n"
      "    assert m.tolist() == [[1.5, -2.25], [1e300, -0.0]], m\n"
      "    assert np.signbit(m[1, 1])\n"
      "    e = d['empty']\n"
      "    assert e.dtype == np.int32 and e.shape == (0,)\n"
      "    n = d['camera_names']\n"
      "    assert n.dtype == np.dtype('<U11'), n.dtype\n"
      "    assert n.tolist() == ['cam0', '\\u03a9mega/1.png'], n.tolist()\n"
      "    assert zipfile.ZipFile(path).testzip() is None\n"
      "d = np.load(sys.argv[3])\n"
      "assert len(d.files) == 65536 and d.files[-1] == 'a65535', d.files[-1]\n"
      "for k in (0, 1, 65534, 65535):\n"
      "    assert d[f'a{k:05d}'].tolist() == [k], k\n"
      "assert zipfile.ZipFile(sys.argv[3]).testzip() is None\n"
      "print('ok')\n",
      {dir + "/plain.npz", dir + "/zip64.npz", dir + "/many.npz"}, &output);
  EXPECT_EQ(code, 0) << output;
  EXPECT_NE(output.find("ok"), std::string::npos) << output;
}

/// The bytes of `path` hold the zip64 end of central directory record's signature.
bool hasZip64EndRecord(const std::string& path) {
  return test::readFile(path).find(std::string("PK\x06\x06", 4)) != std::string::npos;
}

TEST(NpzNumpy, ReadsWhatNumpyWrites) {
  const std::string python = numpyPython();
  if (python.empty()) GTEST_SKIP() << "no Python with NumPy (.venv or APERTURE_TEST_PYTHON)";
  const Fixture f;
  const std::string dir = test::scratchDir();
  // The fixture's arrays as np.savez (stored members; NumPy gives every local header zip64
  // sizes), np.savez_compressed (deflated: refused), and np.savez with zipfile's zip64 threshold
  // lowered to 1 byte: the zip64 extra fields and end records NumPy writes for a member
  // past 4 GiB, on a small file.
  std::string output;
  const int code =
      runPython(python, dir,
                "import sys, zipfile, numpy as np\n"
                "arrays = dict(face_view_count=np.array([7, 0, 4000000000], np.uint32),\n"
                "              matrix=np.array([[1.5, -2.25], [1e300, -0.0]]),\n"
                "              empty=np.zeros(0, np.int32),\n"
                "              camera_names=np.array(['cam0', '\\u03a9mega/1.png']))\n"
                "np.savez(sys.argv[1], **arrays)\n"
                "np.savez_compressed(sys.argv[2], **arrays)\n"
                "zipfile.ZIP64_LIMIT = 1\n"
                "np.savez(sys.argv[3], **arrays)\n"
                "z = zipfile.ZipFile(sys.argv[2])\n"
                "assert all(i.compress_type == zipfile.ZIP_DEFLATED for i in z.infolist())\n"
                "print('ok')\n",
                {dir + "/savez.npz", dir + "/compressed.npz", dir + "/zip64.npz"}, &output);
  ASSERT_EQ(code, 0) << output;
  EXPECT_FALSE(hasZip64EndRecord(dir + "/savez.npz"));
  EXPECT_TRUE(hasZip64EndRecord(dir + "/zip64.npz"));
  for (const char* name : {"savez.npz", "zip64.npz"}) {
    SCOPED_TRACE(name);
    expectRoundTrip(dir + "/" + name, f);
  }
  // Deflated members are refused, naming the file, the member and the method.
  const std::string message = errorOf([&] { readNpz(dir + "/compressed.npz"); });
  EXPECT_NE(message.find(dir + "/compressed.npz"), std::string::npos) << message;
  EXPECT_NE(message.find("face_view_count.npy"), std::string::npos) << message;
  EXPECT_NE(message.find("compression method 8"), std::string::npos) << message;
}

}  // namespace
}  // namespace aperture
