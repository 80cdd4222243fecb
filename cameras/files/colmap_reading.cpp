// Line, token, number and binary reading for COLMAP's files (cameras/files/colmap_reading.h).
#include "cameras/files/colmap_reading.h"

#include <fstream>
#include <sstream>

#include "core/util/mapped_file.h"

namespace aperture::camera_files {

std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(cat(path, ": cannot open the file"));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::pair<int, std::string>> textLines(const std::string& text) {
  std::vector<std::pair<int, std::string>> lines;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const size_t b = line.find_first_not_of(" \t\r");
    const size_t e = line.find_last_not_of(" \t\r");
    lines.emplace_back(number, b == std::string::npos ? "" : line.substr(b, e - b + 1));
  }
  return lines;
}

namespace {

/// Where the token after the one that starts at `pos` starts (npos when none).
size_t nextTokenStart(const std::string& line, size_t pos) {
  return line.find_first_not_of(kTokenSeparators, line.find_first_of(kTokenSeparators, pos));
}

}  // namespace

std::vector<std::string> tokensOf(const std::string& line) {
  std::vector<std::string> tokens;
  for (size_t begin = line.find_first_not_of(kTokenSeparators); begin != std::string::npos;
       begin = nextTokenStart(line, begin))
    tokens.push_back(line.substr(begin, line.find_first_of(kTokenSeparators, begin) - begin));
  return tokens;
}

std::string afterTokens(const std::string& line, size_t count) {
  size_t pos = line.find_first_not_of(kTokenSeparators);
  for (size_t k = 0; k < count && pos != std::string::npos; ++k) pos = nextTokenStart(line, pos);
  return pos == std::string::npos ? std::string() : line.substr(pos);
}

bool isDataLine(const std::string& line) { return !line.empty() && line[0] != '#'; }

double numberToken(const std::string& token, const std::string& context, const char* what) {
  double v = 0;
  if (!parseDoubleToken(token.data(), token.data() + token.size(), v))
    throw Error(cat(context, ": ", what, " '",
                    printableToken(token.data(), token.data() + token.size()),
                    "' is not a number"));
  return v;
}

long long integerToken(const std::string& token, const std::string& context, const char* what,
                       long long lo, long long hi) {
  int64_t v = 0;
  if (!parseIntToken(token.data(), token.data() + token.size(), v) || v < lo || v > hi)
    throw Error(cat(context, ": ", what, " '",
                    printableToken(token.data(), token.data() + token.size()),
                    "' is not an integer in [", lo, ", ", hi, "]"));
  return v;
}

std::string BinaryReader::readName(const std::string& what) {
  const size_t end = bytes_.find('\0', pos_);
  if (end == std::string::npos)
    throw Error(cat(path_, ": truncated: ", what,
                    " has no terminating NUL before the end of the file (", bytes_.size(),
                    " bytes)"));
  std::string name = bytes_.substr(pos_, end - pos_);
  pos_ = end + 1;
  return name;
}

uint64_t BinaryReader::readCount(size_t minBytesEach, const std::string& what) {
  const uint64_t n = read<uint64_t>(what);
  if (n > remaining() / minBytesEach)
    throw Error(cat(path_, ": ", what, " is ", n, ", more than the remaining ", remaining(),
                    " bytes could hold (at least ", minBytesEach, " bytes each)"));
  return n;
}

void BinaryReader::need(size_t n, const std::string& what) const {
  if (n > remaining())
    throw Error(cat(path_, ": truncated: ", what, " needs ", n, " bytes at offset ", pos_,
                    ", the file has ", bytes_.size()));
}

}  // namespace aperture::camera_files
