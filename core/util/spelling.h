#pragma once
// "Did you mean": the closest known word to a misspelt one, for unknown flags, job keys,
// commands, camera types and AOV names.
#include <string>
#include <vector>

namespace aperture {

/// `s` with ASCII letters in lower case.
std::string toLowerAscii(std::string s);

/// Edit distance (insertions, deletions, substitutions, adjacent transpositions).
size_t editDistance(const std::string& a, const std::string& b);

/// The candidate closest to `word` when it is close enough to be a likely typo (distance at
/// most max(1, |word| / 3), case-insensitive), else "".
std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates);

/// " (did you mean 'X'?)" when closestMatch finds X, else "".
std::string didYouMean(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace aperture
