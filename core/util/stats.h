#pragma once
// Summaries of repeated timings (bench, tradeoff): the median and the spread of a sample.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace aperture {

/// The middle value of `v` (the mean of the two middle values for an even count); 0 if empty.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Median, extremes and coefficient of variation of a sample.
struct SampleSummary {
  double median = 0, min = 0, max = 0;
  double cv = 0;  ///< sample standard deviation (n - 1) over the mean; 0 for n < 2 or mean <= 0
};

/// Summarizes `v`; all zeros when it is empty.
inline SampleSummary summarize(const std::vector<double>& v) {
  SampleSummary s;
  if (v.empty()) return s;
  const size_t n = v.size();
  s.median = median(v);
  s.min = *std::min_element(v.begin(), v.end());
  s.max = *std::max_element(v.begin(), v.end());
  double mean = 0, var = 0;
  for (double x : v) mean += x;
  mean /= double(n);
  for (double x : v) var += (x - mean) * (x - mean);
  s.cv = n > 1 && mean > 0 ? std::sqrt(var / double(n - 1)) / mean : 0;
  return s;
}

}  // namespace aperture
