// The live node's ~stats line: its input ledger, clock jumps, updates and their gaps, the
// arrival -> ~markers latency and the model's open-loop predictions on the window, as
// "key=value" fields separated by spaces (scripts and the soak driver parse them by key). No ROS
// here.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "motion_model_estimation/identification/online/migrants.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/live/latency_stats.h"
#include "motion_model_estimation/live/update_gap_stats.h"

namespace mme {

/// The island model's ledger (estimator_node with ~islands/enabled).
struct IslandStats {
  uint64_t sent = 0;               ///< individuals this island emigrated
  MigrationCounters counters;      ///< what it was offered (received, refused, accepted, ...)
  uint64_t batches_from_peers = 0; ///< messages of other islands, refused ones included
  /// [ms] from a peer's send stamp to the arrival here (wall clocks: the same host, or hosts
  /// kept in sync), over the last 1024 batches (nearest rank) and the largest ever; valid once
  /// batches_from_peers > 0.
  double latency_p50_ms = 0.0, latency_p99_ms = 0.0, latency_max_ms = 0.0;
  /// Batches that took longer than their sender's own last period (the time between its
  /// previous batch and this one): they arrived later than one migration period.
  uint64_t batches_late = 0;
  /// [ms] median wall time between two emigrations of this island, over its last 1024 (0
  /// before the second).
  double period_ms = 0.0;
};

struct EstimatorStats {
  InputCounters input;       ///< the estimator's counters (accepted, rejected_time, ...)
  uint64_t rejected = 0;     ///< every frame the node skipped, whatever the reason
  uint64_t clock_jumps = 0;  ///< frames that restarted the window
  UpdateGapSummary updates;  ///< estimate updates and the gaps between them
  LatencySummary latency;    ///< arrival -> ~markers of drawn frames
  std::optional<PredictionReport> prediction;  ///< the model's predictions on the window
  std::string muscles;       ///< ~sensor_muscles' state (MuscleJob::status), "" = off
  int muscle_count = 0;      ///< muscles of the estimated model (0: none yet)
  uint32_t muscle_refits = 0, muscle_refits_adopted = 0;  ///< refits tried / adopted
  double muscle_refit_ms = 0.0;  ///< the last refit's wall time [ms]
  std::string structure;     ///< ~select_structure's state (StructureJob::status), "" = off
  uint32_t structure_selections = 0;  ///< ... and the selections that chose a model
  bool structure_cut = false;  ///< the last selection was cut by its time limit
  std::string structure_error;  ///< why the last selection failed ("" unless failed)
  uint32_t output_error_rejections = 0;  ///< output-error fits not adopted (Estimate's)
  std::optional<IslandStats> islands;    ///< ~islands/enabled only
};

/// "accepted=N rejected=N occluded=N rejected_time=N rejected_size=N clock_jumps=N updates=N
/// markers_published=N" (occluded: hidden markers; after it "model_only=N" when the input had no
/// marker for fixed particles of the model, e.g. anchors: samples masked, not occluded), then "latency_p50_ms=X latency_p99_ms=X" once markers were drawn, then
/// "max_update_gap_ms=X max_update_gap_10s_ms=X update_gap_p99_ms=X" once an update happened
/// (X with 3 decimals), then, when the worker measured where the longest gap went,
/// "max_update_gap_in_update_ms=X max_update_gap_cpu_ms=X max_update_gap_waiting_ms=X" (inside
/// update(), on a core, runnable but waiting for a core), then "output_error_rejections=N"; with ~islands/enabled "migrants_sent=N migrants_received=N
/// migrants_accepted=N migrants_refused=N migrants_dropped=N migrant_batches_from_peers=N", then
/// "migrant_latency_p50_ms=X migrant_latency_p99_ms=X migrant_latency_max_ms=X
/// migrant_batches_late=N" once a peer's batch arrived and "migration_period_ms=X" once this
/// island emigrated twice;
/// then, once a prediction report exists, per horizon K and predictor P (its CSV name: model,
/// constant_velocity, constant_acceleration, gravity_only) "predict<K>_<P>_mm=X" (RMS per
/// coordinate [mm], 3 decimals; horizons without a sample are left out) and
/// "rollout_bounded=0|1"; with ~sensor_muscles "muscles=waiting|fitting|fitted|not_kept|failed
/// muscle_count=N muscle_refits=N muscle_refits_adopted=N muscle_refit_ms=X"; with
/// ~select_structure, "structure_selections=N" (selections that
/// chose a model) and "structure=idle|pending|running|chosen:<level>|failed", then
/// "structure_cut=1" when the time limit cut the last selection, and last, when it failed,
/// "structure_error=<why>" (the rest of the line: the reason has spaces).
std::string formatStats(const EstimatorStats& stats);

}  // namespace mme
