// Median and sample summaries of repeated timings (core/util/stats.h).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/util/stats.h"

namespace aperture {
namespace {

TEST(Stats, MedianOfOddAndEvenCountsAndOfNothing) {
  EXPECT_EQ(median({3, 1, 2}), 2.0);
  EXPECT_EQ(median({4, 1, 3, 2}), 2.5) << "even count: mean of the two middle values";
  EXPECT_EQ(median({}), 0.0);
  // An outlier moves the mean, not the median (why timings are summarized by the median).
  EXPECT_EQ(median({1, 2, 100}), 2.0);
  EXPECT_NE(median({1, 2, 100}), (1 + 2 + 100) / 3.0);
}

TEST(Stats, SummaryUsesTheSampleStandardDeviation) {
  const SampleSummary s = summarize({4, 1, 3, 2});
  EXPECT_EQ(s.median, 2.5);
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 4.0);
  // Mean 2.5; squared deviations 2.25 + 0.25 + 0.25 + 2.25 = 5, over n - 1 = 3.
  EXPECT_DOUBLE_EQ(s.cv, std::sqrt(5.0 / 3.0) / 2.5);
  EXPECT_GT(std::fabs(s.cv - std::sqrt(5.0 / 4.0) / 2.5), 1e-3) << "population (n) divisor";
  EXPECT_EQ(summarize({7}).cv, 0.0);
  EXPECT_EQ(summarize({}).max, 0.0);
}

}  // namespace
}  // namespace aperture
