// ASPRS LAS 1.4 (R15), point data record format 6: the public header block (375 bytes, no
// VLRs) and one 30-byte record per point, every value little-endian (core/util/little_endian.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "core/io/atomic_file.h"
#include "core/points/point_writers.h"
#include "core/util/error.h"
#include "core/util/little_endian.h"

namespace aperture {

namespace {

constexpr uint16_t kLasHeaderSize = 375;
constexpr uint16_t kLasRecordFormat6Size = 30;
constexpr double kLasScale = 0.001;  // millimetres

/// `text` in a fixed char[n] field, zero padded.
void appendFixed(std::string& out, const std::string& text, size_t n) {
  for (size_t k = 0; k < n; ++k) out.push_back(k < text.size() ? text[k] : '\0');
}

const PointField& required(const std::string& path, const PointCloud& cloud, const char* name) {
  const PointField* f = cloud.find(name);
  if (!f) throw Error(cat("cannot write '", path, "': LAS needs the point field '", name, "'"));
  return *f;
}

}  // namespace

void writePointsLas(const std::string& path, const PointCloud& cloud,
                    const PointWriteOptions& options) {
  cloud.check(cat("cannot write '", path, "'"));
  namespace pf = point_fields;
  const PointField* xyz[3] = {&required(path, cloud, pf::kX), &required(path, cloud, pf::kY),
                              &required(path, cloud, pf::kZ)};
  const PointField* intensity = cloud.find(pf::kIntensity);
  const PointField* time = cloud.find(pf::kTime);
  const PointField* ring = cloud.find(pf::kRing);
  const PointField* returnNumber = cloud.find(pf::kReturnNumber);
  const PointField* returns = cloud.find(pf::kReturns);
  const PointField* label = nullptr;
  if (!options.labelField.empty()) {
    label = cloud.find(options.labelField);
    if (!label)
      throw Error(cat("cannot write '", path, "': no label field '", options.labelField, "'"));
  }

  // Box, then an offset per axis at the whole metre nearest its centre.
  double lo[3], hi[3], offset[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<double>::infinity();
    hi[a] = -lo[a];
    for (size_t i = 0; i < cloud.size; ++i) {
      const double v = xyz[a]->value(i);
      if (!std::isfinite(v))
        throw Error(
            cat("cannot write '", path, "': point ", i, " has a non-finite ", xyz[a]->name));
      lo[a] = std::min(lo[a], v);
      hi[a] = std::max(hi[a], v);
    }
    if (cloud.size == 0) lo[a] = hi[a] = 0;
    offset[a] = std::round(0.5 * (lo[a] + hi[a]));
  }

  uint64_t byReturn[15] = {};
  std::string body;
  body.reserve(cloud.size * kLasRecordFormat6Size);
  for (size_t i = 0; i < cloud.size; ++i) {
    for (int a = 0; a < 3; ++a) {
      const double q = std::round((xyz[a]->value(i) - offset[a]) / kLasScale);
      if (!(q >= double(INT32_MIN) && q <= double(INT32_MAX)))
        throw Error(cat("cannot write '", path, "': ", xyz[a]->name, " = ", xyz[a]->value(i),
                        " of point ", i, " does not fit LAS's int32 at millimetre scale"));
      appendLittleEndian(body, int32_t(q));
    }
    const double level = intensity ? std::clamp(intensity->value(i), 0.0, 1.0) : 0.0;
    appendLittleEndian(body, uint16_t(std::lround(level * 65535.0)));
    const uint32_t number = returnNumber ? returnNumber->uintValue(i) : 1u;
    const uint32_t count = returns ? returns->uintValue(i) : 1u;
    if (number < 1 || number > 15 || count < number || count > 15)
      throw Error(cat("cannot write '", path, "': point ", i, " is return ", number, " of ", count,
                      " (LAS: 1 <= return <= returns <= 15)"));
    ++byReturn[number - 1];
    body.push_back(char(number | (count << 4)));
    body.push_back(char(0));  // classification flags, channel 0, scan direction, edge: 0
    const uint32_t classification = label ? label->uintValue(i) : 0u;
    if (classification > 255)
      throw Error(cat("cannot write '", path, "': label field '", options.labelField, "' is ",
                      classification, " at point ", i, " (LAS classification: 0..255)"));
    body.push_back(char(classification));
    const uint32_t userData = ring ? ring->uintValue(i) : 0u;
    body.push_back(char(userData <= 255 ? userData : 0u));
    appendLittleEndian(body, int16_t(0));   // scan angle
    appendLittleEndian(body, uint16_t(0));  // point source id
    const double seconds = cloud.startSeconds + (time ? time->value(i) * 1e-9 : 0.0);
    appendLittleEndian(body, seconds);
  }

  std::string h;
  h.reserve(kLasHeaderSize);
  h += "LASF";
  appendLittleEndian(h, uint16_t(0));  // file source id
  // Bit 4: WKT (R15: must be set for formats 6-10); bit 3: synthetic return numbers, when
  // the returns are layered surfaces rather than a pulse's echoes.
  appendLittleEndian(h, uint16_t((1u << 4) | (returnNumber ? (1u << 3) : 0u)));
  appendFixed(h, "", 16);  // project GUID
  h.push_back(char(1));
  h.push_back(char(4));
  appendFixed(h, "aperture scan", 32);
  appendFixed(h, "aperture", 32);
  appendLittleEndian(h, uint16_t(0));  // creation day: not recorded (files are reproducible)
  appendLittleEndian(h, uint16_t(0));  // creation year
  appendLittleEndian(h, kLasHeaderSize);
  appendLittleEndian(h, uint32_t(kLasHeaderSize));  // offset to point data: no VLRs
  appendLittleEndian(h, uint32_t(0));               // number of VLRs
  h.push_back(char(6));
  appendLittleEndian(h, kLasRecordFormat6Size);
  appendLittleEndian(h, uint32_t(0));  // legacy point count: 0 for formats 6-10
  for (int k = 0; k < 5; ++k) appendLittleEndian(h, uint32_t(0));
  for (int a = 0; a < 3; ++a) appendLittleEndian(h, kLasScale);
  for (int a = 0; a < 3; ++a) appendLittleEndian(h, offset[a]);
  for (int a = 0; a < 3; ++a) {
    appendLittleEndian(h, hi[a]);
    appendLittleEndian(h, lo[a]);
  }
  appendLittleEndian(h, uint64_t(0));  // start of waveform data
  appendLittleEndian(h, uint64_t(0));  // start of first EVLR
  appendLittleEndian(h, uint32_t(0));  // number of EVLRs
  appendLittleEndian(h, uint64_t(cloud.size));
  for (uint64_t n : byReturn) appendLittleEndian(h, n);
  if (h.size() != kLasHeaderSize) throw Error(cat("internal: LAS header of ", h.size(), " bytes"));
  writePiecesAtomically(path, {{h.data(), h.size()}, {body.data(), body.size()}});
}

}  // namespace aperture
