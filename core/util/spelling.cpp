#include "core/util/spelling.h"

#include <algorithm>
#include <cctype>

namespace aperture {

std::string toLowerAscii(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

size_t editDistance(const std::string& a, const std::string& b) {
  // Optimal string alignment distance over three rows of the dynamic-programming table.
  std::vector<size_t> before(b.size() + 1), previous(b.size() + 1), current(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        current[j] = std::min(current[j], before[j - 2] + 1);
    }
    before.swap(previous);
    previous.swap(current);
  }
  return previous[b.size()];
}

std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string w = toLowerAscii(word);
  // A unique candidate that starts with the word ("diag" for "diagonal").
  std::string prefixed;
  size_t prefixes = 0;
  for (const std::string& c : candidates)
    if (w.size() >= 2 && toLowerAscii(c).rfind(w, 0) == 0) ++prefixes, prefixed = c;
  if (prefixes == 1) return prefixed;
  const size_t limit = std::max<size_t>(1, w.size() / 3);
  std::string best;
  size_t bestDistance = limit + 1;
  for (const std::string& c : candidates) {
    const size_t d = editDistance(w, toLowerAscii(c));
    if (d < bestDistance) bestDistance = d, best = c;
  }
  return best;
}

std::string didYouMean(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string m = closestMatch(word, candidates);
  return m.empty() ? std::string() : " (did you mean '" + m + "'?)";
}

}  // namespace aperture
