// LatencyStats: nearest-rank percentiles over the last 1024 latencies, every latency counted.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "motion_model_estimation/live/latency_stats.h"

namespace {

TEST(LatencyStats, NearestRankPercentiles) {
  std::vector<double> v = {5, 1, 4, 2, 3};
  EXPECT_EQ(mme::LatencyStats::percentile(&v, 0.5), 3.0);  // ceil(2.5) = 3rd smallest
  EXPECT_EQ(mme::LatencyStats::percentile(&v, 0.99), 5.0);
  EXPECT_EQ(mme::LatencyStats::percentile(&v, 0.2), 1.0);   // exactly 1 of 5 at or below
  EXPECT_EQ(mme::LatencyStats::percentile(&v, 0.21), 2.0);
  std::vector<double> one = {7.5};
  EXPECT_EQ(mme::LatencyStats::percentile(&one, 0.5), 7.5);
  EXPECT_EQ(mme::LatencyStats::percentile(&one, 0.99), 7.5);
  std::vector<double> none;
  EXPECT_TRUE(std::isnan(mme::LatencyStats::percentile(&none, 0.5)));
  // 1..100 shuffled: p50 = 50, p99 = 99 (not 100: one value in a hundred may be above it).
  std::vector<double> hundred(100);
  for (int i = 0; i < 100; ++i) hundred[i] = i + 1;
  std::shuffle(hundred.begin(), hundred.end(), std::mt19937(3));
  EXPECT_EQ(mme::LatencyStats::percentile(&hundred, 0.5), 50.0);
  EXPECT_EQ(mme::LatencyStats::percentile(&hundred, 0.99), 99.0);
}

TEST(LatencyStats, SummaryIsEmptyUntilTheFirstLatency) {
  mme::LatencyStats stats;
  const mme::LatencySummary s = stats.summary();
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.kept, 0u);
}

TEST(LatencyStats, KeepsTheLast1024AndCountsAll) {
  mme::LatencyStats stats;
  // 1000 slow frames first, then 1024 fast ones: the slow ones have all left the window.
  for (int i = 0; i < 1000; ++i) stats.add(100.0);
  mme::LatencySummary s = stats.summary();
  EXPECT_EQ(s.count, 1000u);
  EXPECT_EQ(s.kept, 1000u);
  EXPECT_EQ(s.p50_ms, 100.0);
  for (int i = 0; i < 1024; ++i) stats.add(0.001 * (i + 1));  // 0.001 .. 1.024 ms
  s = stats.summary();
  EXPECT_EQ(s.count, 2024u);
  EXPECT_EQ(s.kept, 1024u);
  EXPECT_DOUBLE_EQ(s.p50_ms, 0.512);   // the 512th smallest
  EXPECT_DOUBLE_EQ(s.p99_ms, 1.014);   // ceil(0.99 * 1024) = the 1014th smallest
  // One more slow frame: it is kept, the oldest fast one goes, and p99 does not see it alone.
  stats.add(100.0);
  s = stats.summary();
  EXPECT_EQ(s.kept, 1024u);
  EXPECT_DOUBLE_EQ(s.p50_ms, 0.513);
  EXPECT_DOUBLE_EQ(s.p99_ms, 1.015);
}

TEST(LatencyStats, AnotherWindowLength) {
  mme::LatencyStats stats(4);
  for (double v : {9.0, 9.0, 1.0, 2.0, 3.0, 4.0}) stats.add(v);
  const mme::LatencySummary s = stats.summary();
  EXPECT_EQ(s.kept, 4u);
  EXPECT_EQ(s.count, 6u);
  EXPECT_EQ(s.p50_ms, 2.0);
  EXPECT_EQ(s.p99_ms, 4.0);
}

}  // namespace
