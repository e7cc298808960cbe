// formatStats: the ~stats line, field by field, and the fields that wait for their first value.
#include <gtest/gtest.h>

#include "motion_model_estimation/live/estimator_stats.h"

namespace {

TEST(EstimatorStats, CountersOnlyBeforeAnyUpdateOrMarkers) {
  mme::EstimatorStats s;
  s.input.accepted = 120;
  s.input.occluded_samples = 7;
  s.input.rejected_time = 2;
  s.input.rejected_size = 1;
  s.rejected = 5;
  s.clock_jumps = 3;
  EXPECT_EQ(mme::formatStats(s),
            "accepted=120 rejected=5 occluded=7 rejected_time=2 rejected_size=1 clock_jumps=3 "
            "updates=0 markers_published=0");
}

TEST(EstimatorStats, LatencyAndUpdateGapFieldsOnceTheyExist) {
  mme::EstimatorStats s;
  s.input.accepted = 1;
  s.updates.updates = 42;
  s.updates.max_gap_ms = 512.25;
  s.updates.recent_max_gap_ms = 61.0;
  EXPECT_EQ(mme::formatStats(s),
            "accepted=1 rejected=0 occluded=0 rejected_time=0 rejected_size=0 clock_jumps=0 "
            "updates=42 markers_published=0 max_update_gap_ms=512.250 "
            "max_update_gap_10s_ms=61.000");
  s.latency.count = 9;
  s.latency.kept = 9;
  s.latency.p50_ms = 0.2114;
  s.latency.p99_ms = 1.5;
  EXPECT_EQ(mme::formatStats(s),
            "accepted=1 rejected=0 occluded=0 rejected_time=0 rejected_size=0 clock_jumps=0 "
            "updates=42 markers_published=9 latency_p50_ms=0.211 latency_p99_ms=1.500 "
            "max_update_gap_ms=512.250 max_update_gap_10s_ms=61.000");
}

}  // namespace
