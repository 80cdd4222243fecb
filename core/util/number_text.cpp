#include "core/util/number_text.h"

#include <cmath>
#include <sstream>

#include "core/util/error.h"

namespace aperture {

std::vector<double> parseNumbers(const std::string& source, const std::string& text, size_t count,
                                 const char* shape) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    size_t used = 0;
    double x = 0;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size())
      throw Error(
          cat(source, ": '", item, "' in '", text, "' is not a number (expected ", shape, ")"));
    v.push_back(x);
  }
  if (count == 0 && v.empty()) throw Error(cat(source, ": expected ", shape, ", got '", text, "'"));
  if (count != 0 && v.size() != count)
    throw Error(cat(source, ": expected ", shape, " (", count, " comma-separated number",
                    count == 1 ? "" : "s", "), got '", text, "'"));
  return v;
}

namespace {
template <size_t N>
std::vector<double> finiteNumbers(const std::string& source, const std::string& text,
                                  const char* shape) {
  std::vector<double> v = parseNumbers(source, text, N, shape);
  for (double x : v)
    if (!std::isfinite(x)) throw Error(cat(source, ": '", text, "' has a non-finite value"));
  return v;
}
}  // namespace

glm::dvec2 parseVec2(const std::string& source, const std::string& text) {
  const auto v = finiteNumbers<2>(source, text, "A,B");
  return {v[0], v[1]};
}

glm::dvec3 parseVec3(const std::string& source, const std::string& text) {
  const auto v = finiteNumbers<3>(source, text, "X,Y,Z");
  return {v[0], v[1], v[2]};
}

}  // namespace aperture
