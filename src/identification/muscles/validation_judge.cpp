#include "validation_judge.h"

#include <algorithm>
#include <cstdio>

#include "motion_model_estimation/identification/estimators/prediction_error.h"

namespace mme::sensor_muscles {

namespace {

/// The sensor muscles are kept when they predict the validation frames better than the passive
/// model by this share of the larger of its and the constant-velocity guess's errors.
constexpr double kKeepMargin = 0.01;

/// The rollouts a validation may run: this many times its judged frames (evaluatePredictions).
constexpr double kRolloutWindows = 10.0;

}  // namespace

ValidationJudge::ValidationJudge(const Trajectory& data, int horizon_frames, int validation_start)
    : data_(data), horizons_{horizon_frames}, validation_start_(validation_start) {}

void ValidationJudge::judge(const Model& model, double* rms_m, double* constant_velocity_rms_m,
                            bool* bounded) const {
  const PredictionReport report =
      evaluatePredictions(model, data_, horizons_, kRolloutWindows, validation_start_);
  for (const PredictionError& row : report.rows) {
    if (row.predictor == Predictor::kModel) *rms_m = row.rms_m;
    if (row.predictor == Predictor::kConstantVelocity && constant_velocity_rms_m)
      *constant_velocity_rms_m = row.rms_m;
  }
  if (bounded) *bounded = report.rollout_bounded;
}

void decideKept(bool candidate_bounded, bool refit_bounded, size_t refits_tried, SensorMuscleResult* result) {
  // Better by a margin: where the passive model already explains the data (synthetic data
  // without a controller, noiseless or not), a fit of its residue is no better than the passive
  // model in any sense that matters, and without the margin round-off decided whether silent
  // muscles were written.
  const double margin_m = kKeepMargin * std::max(result->passive_rms_m, result->constant_velocity_rms_m);
  const bool better = result->validation_rms_m < result->passive_rms_m - margin_m;
  result->better_than_passive = refit_bounded && candidate_bounded && better;
  char why[240] = "";
  if (!candidate_bounded)
    std::snprintf(why, sizeof(why), "no candidate's 10x validation rollout stayed bounded");
  else if (!refit_bounded)
    std::snprintf(why, sizeof(why), "every refit on all frames tried (%zu) left the data over its "
                  "10x rollouts", refits_tried);
  else if (!better)
    std::snprintf(why, sizeof(why), "its validation error %.3g m is not below the passive model's "
                  "%.3g m by %.3g m, 1 %% of the larger of it and the constant-velocity guess's",
                  result->validation_rms_m, result->passive_rms_m, margin_m);
  result->not_kept_because = why;
}

}  // namespace mme::sensor_muscles
