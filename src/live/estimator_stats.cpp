#include "motion_model_estimation/live/estimator_stats.h"

#include <cstdio>

namespace mme {

namespace {

/// The island model's fields of the ~stats line (formatStats).
std::string formatIslandStats(const IslandStats& s) {
  std::string text = " migrants_sent=" + std::to_string(s.sent) +
                     " migrants_received=" + std::to_string(s.counters.received) +
                     " migrants_accepted=" + std::to_string(s.counters.accepted) +
                     " migrants_refused=" + std::to_string(s.counters.refused) +
                     " migrants_dropped=" + std::to_string(s.counters.dropped) +
                     " migrant_batches_from_peers=" + std::to_string(s.batches_from_peers);
  char field[128];
  if (s.batches_from_peers > 0) {
    std::snprintf(field, sizeof(field),
                  " migrant_latency_p50_ms=%.3f migrant_latency_p99_ms=%.3f migrant_latency_max_ms=%.3f",
                  s.latency_p50_ms, s.latency_p99_ms, s.latency_max_ms);
    text += field;
    text += " migrant_batches_late=" + std::to_string(s.batches_late);
  }
  if (s.period_ms > 0.0) {
    std::snprintf(field, sizeof(field), " migration_period_ms=%.3f", s.period_ms);
    text += field;
  }
  return text;
}

}  // namespace

std::string formatStats(const EstimatorStats& s) {
  std::string text =
      "accepted=" + std::to_string(s.input.accepted) + " rejected=" + std::to_string(s.rejected) +
      " occluded=" + std::to_string(s.input.occluded_samples) +
      (s.input.model_only_samples > 0
           ? " model_only=" + std::to_string(s.input.model_only_samples)
           : std::string()) +
      " rejected_time=" + std::to_string(s.input.rejected_time) +
      " rejected_size=" + std::to_string(s.input.rejected_size) +
      " clock_jumps=" + std::to_string(s.clock_jumps) +
      " updates=" + std::to_string(s.updates.updates) +
      " markers_published=" + std::to_string(s.latency.count);
  char field[128];
  if (s.latency.kept > 0) {
    std::snprintf(field, sizeof(field), " latency_p50_ms=%.3f latency_p99_ms=%.3f",
                  s.latency.p50_ms, s.latency.p99_ms);
    text += field;
  }
  if (s.updates.updates > 0) {
    std::snprintf(field, sizeof(field), " max_update_gap_ms=%.3f max_update_gap_10s_ms=%.3f update_gap_p99_ms=%.3f",
                  s.updates.max_gap_ms, s.updates.recent_max_gap_ms, s.updates.p99_gap_ms);
    text += field;
    const UpdateGapBreakdown& b = s.updates.max_gap_breakdown;
    if (b.known) {
      std::snprintf(field, sizeof(field),
                    " max_update_gap_in_update_ms=%.3f max_update_gap_cpu_ms=%.3f max_update_gap_waiting_ms=%.3f",
                    1e3 * b.in_update_s, 1e3 * b.on_cpu_s, 1e3 * b.waiting_s);
      text += field;
    }
    text += " output_error_rejections=" + std::to_string(s.output_error_rejections);
  }
  if (s.prediction) {
    for (const PredictionError& row : s.prediction->rows) {
      if (row.samples == 0) continue;
      std::snprintf(field, sizeof(field), " predict%d_%s_mm=%.3f", row.horizon,
                    predictorName(row.predictor), 1e3 * row.rms_m);
      text += field;
    }
    text += s.prediction->rollout_bounded ? " rollout_bounded=1" : " rollout_bounded=0";
  }
  if (s.islands) text += formatIslandStats(*s.islands);
  if (!s.muscles.empty()) {
    text += " muscles=" + s.muscles + " muscle_count=" + std::to_string(s.muscle_count) +
            " muscle_refits=" + std::to_string(s.muscle_refits) +
            " muscle_refits_adopted=" + std::to_string(s.muscle_refits_adopted);
    std::snprintf(field, sizeof(field), " muscle_refit_ms=%.3f", s.muscle_refit_ms);
    text += field;
  }
  if (!s.structure.empty()) {
    text += " structure_selections=" + std::to_string(s.structure_selections) + " structure=" + s.structure;
    if (s.structure_cut) text += " structure_cut=1";
    if (!s.structure_error.empty()) {
      std::string why = s.structure_error;  // one line: ~stats is read line by line
      for (char& c : why)
        if (c == '\n' || c == '\r') c = ' ';
      text += " structure_error=" + why;
    }
  }
  return text;
}

}  // namespace mme
