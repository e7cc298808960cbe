// formatStats: the ~stats line, field by field, and the fields that wait for their first value
// (latency, update gaps, the model's predictions).
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

// Samples of model particles without a marker (anchors) are not occluded markers: they have a
// field of their own, shown once there are some.
TEST(EstimatorStats, ModelOnlySamplesAreApartFromTheOccludedOnes) {
  mme::EstimatorStats s;
  s.input.accepted = 121;
  s.input.occluded_samples = 2;
  s.input.model_only_samples = 363;
  EXPECT_EQ(mme::formatStats(s),
            "accepted=121 rejected=0 occluded=2 model_only=363 rejected_time=0 rejected_size=0 "
            "clock_jumps=0 updates=0 markers_published=0");
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
            "max_update_gap_10s_ms=61.000 update_gap_p99_ms=0.000 output_error_rejections=0");
  s.latency.count = 9;
  s.latency.kept = 9;
  s.latency.p50_ms = 0.2114;
  s.latency.p99_ms = 1.5;
  EXPECT_EQ(mme::formatStats(s),
            "accepted=1 rejected=0 occluded=0 rejected_time=0 rejected_size=0 clock_jumps=0 "
            "updates=42 markers_published=9 latency_p50_ms=0.211 latency_p99_ms=1.500 "
            "max_update_gap_ms=512.250 max_update_gap_10s_ms=61.000 update_gap_p99_ms=0.000 "
            "output_error_rejections=0");
  s.updates.p99_gap_ms = 97.0;
  s.updates.max_gap_breakdown = {0.5, 0.125, 0.25, true};
  EXPECT_EQ(mme::formatStats(s),
            "accepted=1 rejected=0 occluded=0 rejected_time=0 rejected_size=0 clock_jumps=0 "
            "updates=42 markers_published=9 latency_p50_ms=0.211 latency_p99_ms=1.500 "
            "max_update_gap_ms=512.250 max_update_gap_10s_ms=61.000 update_gap_p99_ms=97.000 "
            "max_update_gap_in_update_ms=500.000 max_update_gap_cpu_ms=125.000 "
            "max_update_gap_waiting_ms=250.000 output_error_rejections=0");
}

TEST(EstimatorStats, PredictionFieldsPerHorizonAndPredictorInMillimetres) {
  mme::EstimatorStats s;
  mme::PredictionReport r;
  r.rows.push_back({1, mme::Predictor::kModel, 2.5e-5, 300});
  r.rows.push_back({1, mme::Predictor::kConstantVelocity, 1.25e-3, 300});
  r.rows.push_back({10, mme::Predictor::kModel, 0.0, 0});  // beyond the window: left out
  r.rows.push_back({10, mme::Predictor::kGravityOnly, 0.0123456, 120});
  r.rollout_bounded = false;
  s.prediction = r;
  EXPECT_EQ(mme::formatStats(s),
            "accepted=0 rejected=0 occluded=0 rejected_time=0 rejected_size=0 clock_jumps=0 "
            "updates=0 markers_published=0 predict1_model_mm=0.025 "
            "predict1_constant_velocity_mm=1.250 predict10_gravity_only_mm=12.346 "
            "rollout_bounded=0");
  s.prediction->rollout_bounded = true;
  EXPECT_NE(mme::formatStats(s).find(" rollout_bounded=1"), std::string::npos);
}

TEST(EstimatorStats, MuscleFieldsBeforeTheStructureWhenSensorMusclesAreOn) {
  mme::EstimatorStats s;
  EXPECT_EQ(mme::formatStats(s).find("muscles="), std::string::npos);
  s.muscles = "fitted";
  s.muscle_count = 41;
  s.muscle_refits = 12;
  s.muscle_refits_adopted = 9;
  s.muscle_refit_ms = 35.25;
  s.structure = "chosen:springs";
  s.structure_selections = 1;
  const std::string line = mme::formatStats(s);
  const std::string fields = " muscles=fitted muscle_count=41 muscle_refits=12 muscle_refits_adopted=9 "
                             "muscle_refit_ms=35.250 structure_selections=1";
  EXPECT_NE(line.find(fields), std::string::npos) << line;
}

TEST(EstimatorStats, StructureStateLastWhenSelectionIsOn) {
  mme::EstimatorStats s;
  EXPECT_EQ(mme::formatStats(s).find("structure="), std::string::npos);
  s.structure = "chosen:springs+dampers";
  s.structure_selections = 2;
  const std::string line = mme::formatStats(s);
  EXPECT_EQ(line.substr(line.size() - 56), " structure_selections=2 structure=chosen:springs+dampers");
}

TEST(EstimatorStats, AFailedSelectionSaysWhyOnOneLineAndACutOneIsFlagged) {
  mme::EstimatorStats s;
  s.structure = "chosen:springs";
  s.structure_selections = 1;
  s.structure_cut = true;
  EXPECT_NE(mme::formatStats(s).find(" structure=chosen:springs structure_cut=1"), std::string::npos);
  s.structure = "failed";
  s.structure_cut = false;
  s.structure_error = "structure selection: 30 frames are too few\n(need 35)";
  const std::string line = mme::formatStats(s);
  EXPECT_EQ(line.find("structure_cut"), std::string::npos);
  const std::string tail = " structure=failed structure_error=structure selection: 30 frames are too few (need 35)";
  ASSERT_GE(line.size(), tail.size());
  EXPECT_EQ(line.substr(line.size() - tail.size()), tail);
}

// The estimate's rejected output-error fits appear with the update fields; the island model's
// ledger only with ~islands/enabled, its latency once a peer's batch came and its period once
// this island emigrated twice.
TEST(EstimatorStats, OutputErrorRejectionsAndTheIslandsLedger) {
  mme::EstimatorStats s;
  s.updates.updates = 3;
  s.output_error_rejections = 2;
  const std::string base = mme::formatStats(s);
  EXPECT_NE(base.find(" output_error_rejections=2"), std::string::npos) << base;
  EXPECT_EQ(base.find("migrants_"), std::string::npos) << base;
  mme::IslandStats islands;
  islands.sent = 12;
  islands.counters.received = 9;
  islands.counters.accepted = 4;
  islands.counters.refused = 3;
  islands.counters.dropped = 1;
  s.islands = islands;
  EXPECT_EQ(mme::formatStats(s), base + " migrants_sent=12 migrants_received=9 migrants_accepted=4 "
                                        "migrants_refused=3 migrants_dropped=1 migrant_batches_from_peers=0");
  s.islands->batches_from_peers = 4;
  s.islands->latency_p50_ms = 1.25;
  s.islands->latency_p99_ms = 3.0;
  s.islands->latency_max_ms = 3.5;
  s.islands->batches_late = 1;
  s.islands->period_ms = 400.0;
  EXPECT_EQ(mme::formatStats(s), base + " migrants_sent=12 migrants_received=9 migrants_accepted=4 "
                                        "migrants_refused=3 migrants_dropped=1 migrant_batches_from_peers=4 "
                                        "migrant_latency_p50_ms=1.250 migrant_latency_p99_ms=3.000 "
                                        "migrant_latency_max_ms=3.500 migrant_batches_late=1 "
                                        "migration_period_ms=400.000");
}

}  // namespace
