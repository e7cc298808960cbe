// UpdateGapStats: the longest gap between updates over the run and over the last 10 s, the
// open gap included, nothing before the first update; the gaps' 99th percentile and where the
// longest one's time went.
#include <gtest/gtest.h>

#include "motion_model_estimation/live/update_gap_stats.h"

namespace {

TEST(UpdateGapStats, NothingBeforeTheFirstUpdate) {
  mme::UpdateGapStats stats;
  const mme::UpdateGapSummary s = stats.summary(100.0);
  EXPECT_EQ(s.updates, 0u);
  EXPECT_EQ(s.max_gap_ms, 0.0);
  EXPECT_EQ(s.recent_max_gap_ms, 0.0);
  EXPECT_EQ(stats.updates(), 0u);
}

TEST(UpdateGapStats, LongestGapOverTheRunAndOverTheLast10s) {
  mme::UpdateGapStats stats;
  // Start-up waits do not count: the first gap is from the first update.
  stats.onUpdate(50.0);
  stats.onUpdate(50.1);
  stats.onUpdate(50.8);  // a 0.7 s gap ending at 50.8
  for (int k = 1; k <= 99; ++k) stats.onUpdate(50.8 + 0.1 * k);  // then every 0.1 s to 60.7
  EXPECT_EQ(stats.updates(), 102u);
  mme::UpdateGapSummary s = stats.summary(60.79);
  EXPECT_EQ(s.updates, 102u);
  EXPECT_NEAR(s.max_gap_ms, 700.0, 1e-6);
  EXPECT_NEAR(s.recent_max_gap_ms, 700.0, 1e-6);  // it ended 9.99 s ago
  stats.onUpdate(60.8);
  s = stats.summary(60.85);  // it ended 10.05 s ago
  EXPECT_EQ(s.updates, 103u);
  EXPECT_NEAR(s.max_gap_ms, 700.0, 1e-6);
  EXPECT_NEAR(s.recent_max_gap_ms, 100.0, 1e-6);
}

TEST(UpdateGapStats, TheOpenGapCountsSoAStallShowsAtOnce) {
  mme::UpdateGapStats stats;
  stats.onUpdate(0.0);
  stats.onUpdate(0.2);
  mme::UpdateGapSummary s = stats.summary(0.25);
  EXPECT_NEAR(s.max_gap_ms, 200.0, 1e-9);
  EXPECT_NEAR(s.recent_max_gap_ms, 200.0, 1e-9);
  // The worker stalls: 3 s later, without a new update, both already show it.
  s = stats.summary(3.2);
  EXPECT_NEAR(s.max_gap_ms, 3000.0, 1e-9);
  EXPECT_NEAR(s.recent_max_gap_ms, 3000.0, 1e-9);
  // It recovers; the stall stays the run's maximum, and leaves the recent one after 10 s.
  stats.onUpdate(4.0);
  for (int k = 1; k <= 120; ++k) stats.onUpdate(4.0 + 0.1 * k);  // to 16.0
  s = stats.summary(16.0);
  EXPECT_NEAR(s.max_gap_ms, 3800.0, 1e-6);
  EXPECT_NEAR(s.recent_max_gap_ms, 100.0, 1e-6);
}

TEST(UpdateGapStats, AnotherRecentWindow) {
  mme::UpdateGapStats stats(1.0);
  stats.onUpdate(0.0);
  stats.onUpdate(0.5);
  stats.onUpdate(0.6);
  EXPECT_NEAR(stats.summary(0.9).recent_max_gap_ms, 500.0, 1e-9);
  // The 0.5 s gap ended more than 1 s ago; the open one (0.95 s) is the longest now.
  EXPECT_NEAR(stats.summary(1.55).recent_max_gap_ms, 950.0, 1e-9);
  EXPECT_NEAR(stats.summary(1.55).max_gap_ms, 950.0, 1e-9);
}

TEST(UpdateGapStats, NinetyNinthPercentileOfTheClosedGaps) {
  mme::UpdateGapStats stats;
  EXPECT_EQ(stats.summary(0.0).p99_gap_ms, 0.0);
  double t = 0.0;
  stats.onUpdate(t);
  for (int k = 0; k < 990; ++k) stats.onUpdate(t += 0.0505);  // 990 gaps of 50.5 ms
  for (int k = 0; k < 10; ++k) stats.onUpdate(t += 0.3005);   // 10 of 300.5 ms: the top 1 %
  mme::UpdateGapSummary s = stats.summary(t);
  EXPECT_NEAR(s.p99_gap_ms, 51.0, 1e-9);  // the upper edge of the 1-ms bin of rank 990
  stats.onUpdate(t += 0.3005);  // one more long gap: 11 of 1001 above, rank 991 among them
  EXPECT_NEAR(stats.summary(t).p99_gap_ms, 301.0, 1e-9);
  stats.onUpdate(t += 12.0);  // beyond the bins: counted in the last, reported as the largest
  for (int k = 0; k < 5; ++k) stats.onUpdate(t += 12.0);
  EXPECT_NEAR(stats.summary(t).p99_gap_ms, 301.0, 1e-9);
}

TEST(UpdateGapStats, TheLongestGapKeepsItsBreakdown) {
  mme::UpdateGapStats stats;
  stats.onUpdate(0.0);
  stats.onUpdate(0.1, {0.09, 0.08, 0.005, true});
  stats.onUpdate(0.9, {0.75, 0.1, 0.6, true});  // the longest: mostly waiting for a core
  stats.onUpdate(1.0, {0.09, 0.09, 0.0, true});
  const mme::UpdateGapSummary s = stats.summary(1.0);
  EXPECT_NEAR(s.max_gap_ms, 800.0, 1e-9);
  EXPECT_TRUE(s.max_gap_breakdown.known);
  EXPECT_EQ(s.max_gap_breakdown.in_update_s, 0.75);
  EXPECT_EQ(s.max_gap_breakdown.on_cpu_s, 0.1);
  EXPECT_EQ(s.max_gap_breakdown.waiting_s, 0.6);
  mme::UpdateGapStats unmeasured;
  unmeasured.onUpdate(0.0);
  unmeasured.onUpdate(1.0);
  EXPECT_FALSE(unmeasured.summary(1.0).max_gap_breakdown.known);
}

}  // namespace
