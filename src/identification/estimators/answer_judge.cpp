#include "motion_model_estimation/identification/estimators/answer_judge.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"

namespace mme {

namespace {

/// A figure beyond this many times the data's extent (the free particles' bounding-box diagonal)
/// means the predictions left the data for good (or the finite numbers: evaluatePredictions
/// scores such a sample 1e300 m^2): the model blew up.
constexpr double kBlownUpExtents = 1e3;

}  // namespace

double judgedPredictionRms_m(const Model& model, const Trajectory& trajectory, int horizon_frames) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (horizon_frames < 1 || trajectory.numFrames() < 4) return nan;
  PredictionReport report;
  try {
    // No long rollout: the figure is the K-frame prediction alone.
    report = evaluatePredictions(model, trajectory, {horizon_frames}, 0.0);
  } catch (const std::exception&) {  // no start, or a model the simulator refuses
    return nan;
  }
  for (const PredictionError& row : report.rows) {
    if (row.predictor != Predictor::kModel) continue;
    if (row.samples == 0) return nan;
    const double extent_m =
        RolloutBound::of(model, prepareObservations(model, trajectory), 0, trajectory.numFrames()).extent_m;
    if (!std::isfinite(row.rms_m) || row.rms_m > kBlownUpExtents * extent_m)
      return std::numeric_limits<double>::infinity();
    return row.rms_m;
  }
  return nan;
}

bool replacesStanding(double candidate_rms_m, double standing_rms_m) {
  if (std::isinf(candidate_rms_m)) return false;
  if (std::isnan(candidate_rms_m)) return std::isnan(standing_rms_m);
  if (!std::isfinite(standing_rms_m)) return true;
  return candidate_rms_m <= (1.0 + kJudgeTolerance) * standing_rms_m;
}

bool outputErrorReplacesOneStep(double output_error_rms_m, double one_step_rms_m,
                                double residual_std_m, double noise_std_m) {
  if (replacesStanding(output_error_rms_m, one_step_rms_m)) return true;
  const bool at_noise = std::isfinite(residual_std_m) && noise_std_m > 0.0 &&
                        residual_std_m <= kAtNoiseFactor * noise_std_m;
  return at_noise && std::isfinite(output_error_rms_m);
}

std::string formatJudged(double rms_m) {
  if (std::isinf(rms_m)) return "blew up";
  if (std::isnan(rms_m)) return "not judged";
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g mm", rms_m * 1e3);
  return text;
}

}  // namespace mme
