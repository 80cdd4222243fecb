#pragma once
// Numbers as users type them on a command line: "1.5", "0,1,0". Each number is parsed
// exactly (std::stod of the whole item), so "1e-3" and "-0" work and "1,2a" does not.
#include <glm/glm.hpp>
#include <string>
#include <vector>

namespace aperture {

/// Parses `count` comma-separated numbers (count 0: any number, at least one); throws Error naming
/// `source` (a flag or key), the text and the expected `shape` ("X,Y,Z") for anything else. Values
/// may be non-finite.
std::vector<double> parseNumbers(const std::string& source, const std::string& text, size_t count,
                                 const char* shape);

/// Two or three comma-separated finite numbers ("A,B", "X,Y,Z").
glm::dvec2 parseVec2(const std::string& source, const std::string& text);
glm::dvec3 parseVec3(const std::string& source, const std::string& text);

}  // namespace aperture
