#include "core/points/point_cloud.h"

#include <set>

#include "core/util/error.h"

namespace aperture {

bool isStandardPointField(const std::string& name) {
  namespace pf = point_fields;
  for (const char* f : {pf::kX, pf::kY, pf::kZ, pf::kRange, pf::kTime, pf::kRing, pf::kColumn,
                        pf::kAzimuth, pf::kIncidence, pf::kPrimId, pf::kGeomId, pf::kInstance,
                        pf::kIntensity, pf::kReturnNumber, pf::kReturns})
    if (name == f) return true;
  return false;
}

const char* npyDescrOf(PointType type) {
  switch (type) {
    case PointType::UInt8:
      return "|u1";
    case PointType::UInt16:
      return "<u2";
    case PointType::UInt32:
      return "<u4";
    case PointType::Float32:
      return "<f4";
    case PointType::Float64:
      return "<f8";
  }
  return "<f4";
}

size_t pointTypeSize(PointType type) {
  switch (type) {
    case PointType::UInt8:
      return 1;
    case PointType::UInt16:
      return 2;
    case PointType::UInt32:
    case PointType::Float32:
      return 4;
    case PointType::Float64:
      return 8;
  }
  return 4;
}

namespace {

/// The value of type T stored at `p` (which need not be aligned for T).
template <class T>
T loadAs(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

}  // namespace

double PointField::value(size_t i) const {
  const unsigned char* p = bytes.data() + i * pointTypeSize(type);
  switch (type) {
    case PointType::UInt8:
      return double(*p);
    case PointType::UInt16:
      return double(loadAs<uint16_t>(p));
    case PointType::UInt32:
      return double(loadAs<uint32_t>(p));
    case PointType::Float32:
      return double(loadAs<float>(p));
    case PointType::Float64:
      return loadAs<double>(p);
  }
  return 0;
}

uint32_t PointField::uintValue(size_t i) const {
  if (type == PointType::UInt32) return loadAs<uint32_t>(bytes.data() + 4 * i);
  return uint32_t(value(i));
}

const PointField* PointCloud::find(const std::string& name) const {
  for (const PointField& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

PointField* PointCloud::find(const std::string& name) {
  for (PointField& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

PointField& PointCloud::addField(const std::string& name, PointType type, bool zeroed) {
  LargeBuffer<unsigned char> bytes;
  if (zeroed) bytes.assign(size * pointTypeSize(type), 0);
  return addField(name, type, std::move(bytes));
}

PointField& PointCloud::addField(const std::string& name, PointType type,
                                 LargeBuffer<unsigned char>&& storage) {
  if (find(name)) throw Error(cat("point field '", name, "' is given twice"));
  PointField f;
  f.name = name;
  f.type = type;
  f.bytes = std::move(storage);
  resizeOnHugePages(f.bytes, size * pointTypeSize(type));
  fields.push_back(std::move(f));
  return fields.back();
}

void PointCloud::check(const std::string& what) const {
  std::set<std::string> names;
  for (const PointField& f : fields) {
    if (f.name.empty() || !names.insert(f.name).second)
      throw Error(cat(what, ": point field '", f.name, "' is empty or given twice"));
    if (f.count() != size || f.bytes.size() != size * pointTypeSize(f.type))
      throw Error(cat(what, ": point field '", f.name, "' holds ", f.count(), " values for ", size,
                      " points"));
  }
}

const PointField* RangeImage::find(const std::string& name) const {
  for (const PointField& f : channels)
    if (f.name == name) return &f;
  return nullptr;
}

PointField& RangeImage::addChannel(const std::string& name, PointType type) {
  if (find(name)) throw Error(cat("range image channel '", name, "' is given twice"));
  PointField f;
  f.name = name;
  f.type = type;
  f.bytes.assign(size_t(rows) * size_t(columns) * pointTypeSize(type), 0);
  channels.push_back(std::move(f));
  return channels.back();
}

PointField destagger(const PointField& staggered, int rows, int columns,
                     const std::vector<int>& pixelShiftByRow, bool inverse) {
  if (pixelShiftByRow.size() != size_t(rows))
    throw Error(cat("destagger: ", pixelShiftByRow.size(), " pixel shifts for ", rows, " rows"));
  const size_t item = pointTypeSize(staggered.type);
  if (staggered.bytes.size() != size_t(rows) * size_t(columns) * item)
    throw Error(cat("destagger: channel '", staggered.name, "' is not ", rows, "x", columns));
  PointField out = staggered;
  const long w = columns;
  for (int u = 0; u < rows; ++u) {
    const long shift = (inverse ? -1 : 1) * long(pixelShiftByRow[size_t(u)]);
    const long offset = ((shift % w) + w) % w;
    const unsigned char* in = staggered.bytes.data() + size_t(u) * size_t(w) * item;
    unsigned char* row = out.bytes.data() + size_t(u) * size_t(w) * item;
    for (long c = 0; c < w; ++c)
      std::memcpy(row + size_t((c + offset) % w) * item, in + size_t(c) * item, item);
  }
  return out;
}

}  // namespace aperture
