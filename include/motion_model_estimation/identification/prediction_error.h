// The held-out judge of a model: how well it predicts the markers K frames ahead, open loop,
// next to three guesses that need no model (constant velocity, constant acceleration from the last
// three frames, free fall under the model's gravity). A model that cannot beat an extrapolation
// has not explained the motion.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// The predictors compared, by their CSV names.
enum class Predictor { kModel, kConstantVelocity, kConstantAcceleration, kGravityOnly };
const char* predictorName(Predictor predictor);  ///< "model", "constant_velocity", ...

struct PredictionError {
  int horizon = 0;                 ///< K [frames]
  Predictor predictor = Predictor::kModel;
  double rms_m = 0.0;              ///< RMS per coordinate over every predicted sample observed [m]
  long samples = 0;                ///< observed samples compared (x, y, z each count once)
};

struct PredictionReport {
  std::vector<PredictionError> rows;  ///< per horizon, the four predictors in enum order
  int starts = 0;                     ///< start frames used
  /// A rollout of the model from the first start, `rollout_frames` long, stays finite and within
  /// 10x the data's extent around its centre.
  bool rollout_bounded = false;
  int rollout_frames = 0;
};

/// A prediction starts at every frame t where every free particle is seen, and seen again at most
/// 3 frames before: the model from x(t) with v = (x(t) - x(t-j)) / (j h) for the latest such
/// frame t-j (j = 1, the paper's start, wherever the particle is seen at t-1). A particle is
/// scored at x(t + K) when it is seen there and at t-2, t-1 and t (so that every guess is
/// defined), with the same samples for every predictor. `model` carries every free value;
/// `trajectory` has its particles as markers. Throws InputError on unusable input (no frame
/// rate, horizons < 1, no start).
PredictionReport evaluatePredictions(const Model& model, const Trajectory& trajectory,
                                     const std::vector<int>& horizons,
                                     double rollout_factor = 10.0);

}  // namespace mme
