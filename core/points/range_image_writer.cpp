// Range images (beams × columns, the sensor's own layout) as .npz and EXR, each channel staggered
// as the sensor sends it and, for sensors with pixel shifts (Ouster), destaggered beside it.
#include <deque>
#include <string>
#include <vector>

#include "core/exr/exr_channels.h"
#include "core/io/npz.h"
#include "core/points/point_writers.h"
#include "core/util/error.h"

namespace aperture {

namespace {

void checkImage(const std::string& path, const RangeImage& image) {
  if (image.rows <= 0 || image.columns <= 0)
    throw Error(
        cat("cannot write '", path, "': empty range image ", image.rows, "x", image.columns));
  const size_t pixels = size_t(image.rows) * size_t(image.columns);
  for (const PointField& c : image.channels)
    if (c.count() != pixels)
      throw Error(cat("cannot write '", path, "': channel '", c.name, "' holds ", c.count(),
                      " values for ", image.rows, "x", image.columns, " pixels"));
  if (!image.pixelShiftByRow.empty() && image.pixelShiftByRow.size() != size_t(image.rows))
    throw Error(cat("cannot write '", path, "': ", image.pixelShiftByRow.size(),
                    " pixel shifts for ", image.rows, " rows"));
}

/// The channels to write: the image's, then (with pixel shifts) each destaggered as
/// "destaggered.NAME".
std::deque<PointField> channelsOf(const RangeImage& image) {
  std::deque<PointField> out(image.channels.begin(), image.channels.end());
  if (image.pixelShiftByRow.empty()) return out;
  for (const PointField& c : image.channels) {
    PointField d = destagger(c, image.rows, image.columns, image.pixelShiftByRow);
    d.name = "destaggered." + c.name;
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace

void writeRangeImageNpz(const std::string& path, const RangeImage& image) {
  checkImage(path, image);
  const std::deque<PointField> channels = channelsOf(image);
  std::vector<NpzArray> arrays;
  const std::vector<uint64_t> shape = {uint64_t(image.rows), uint64_t(image.columns)};
  for (const PointField& c : channels)
    arrays.push_back({c.name, npyDescrOf(c.type), shape, c.bytes.data(), c.bytes.size()});
  std::vector<int32_t> shifts(image.pixelShiftByRow.begin(), image.pixelShiftByRow.end());
  if (!shifts.empty())
    arrays.push_back(
        {"pixel_shift_by_row", "<i4", {uint64_t(shifts.size())}, shifts.data(), 4 * shifts.size()});
  writeNpz(path, arrays);
}

void writeRangeImageExr(const std::string& path, const RangeImage& image) {
  checkImage(path, image);
  const std::deque<PointField> channels = channelsOf(image);
  const size_t pixels = size_t(image.rows) * size_t(image.columns);
  std::vector<ExrChannel> exr;
  for (const PointField& c : channels) {
    ExrChannel e;
    e.name = c.name;
    if (c.type == PointType::Float32 || c.type == PointType::Float64) {
      e.floats.resize(pixels);
      for (size_t i = 0; i < pixels; ++i) e.floats[i] = float(c.value(i));
    } else {
      e.uints.resize(pixels);
      for (size_t i = 0; i < pixels; ++i) e.uints[i] = c.uintValue(i);
    }
    exr.push_back(std::move(e));
  }
  std::vector<std::pair<std::string, std::string>> strings;
  if (!image.pixelShiftByRow.empty())
    strings.push_back({"aperture.pixel_shift_by_row",
                       join(image.pixelShiftByRow, " ", [](int s) { return std::to_string(s); })});
  writeExrChannels(path, image.columns, image.rows, exr, strings);
}

void writeRangeImage(const std::string& path, const RangeImage& image) {
  const PointFormat format = pointFormatOf(path);
  if (format == PointFormat::Npz) return writeRangeImageNpz(path, image);
  if (format == PointFormat::Exr) return writeRangeImageExr(path, image);
  throw Error(cat("cannot write '", path, "': a point-cloud format, not a range image"));
}

}  // namespace aperture
